#pragma once
// Where a recording and its simulation differ: the cells whose mean residual is significant, and
// the clock shift that best aligns them per leg direction and separation band.
#include <string>
#include <vector>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"

namespace dw::analysis {

// The cells whose mean residual exceeds z_min (the standard error with the sample count reduced by
// the effective-sample factor), strongest first, at most kMaxRegions.
std::vector<Region> locate(const ExplainData& d, const std::vector<Wrench6>& pred, double factor, double z_min,
                           const std::string& formation);
inline constexpr std::size_t kMaxRegions = 8;

// Per leg direction and separation band: the clock shift (within ± o.shift_half_width_s) that
// best aligns the recording and the model `base`.
std::vector<Shift> shifts(const ExplainData& d, const physics::PhysicsConfig& base, const ExplainOptions& o);

}  // namespace dw::analysis
