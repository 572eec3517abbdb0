#pragma once
// A learnt discrepancy (Kennedy & O'Hagan 2001; FLIGHT_FORMAT.md: "a learnt discrepancy: what
// remains after the accepted effects, modelled as a function of the geometry, with its held-out
// figures"). What the accepted effects leave is regressed, per axis, on smooth functions of where
// the neighbours are — Gaussian bumps over each neighbour's horizontal offset and height above the
// sufferer, summed over the neighbours, also times the offset's direction (a lateral push points
// along it) — with a constant and the sufferer's own velocity and acceleration (zero on a stand:
// a flying sufferer's force estimate m a − thrust errs with its own motion), and a slow drift. Ridge regression,
// fitted on each fold's training blocks and judged on its held-out blocks by the candidates' rule
// (the same pieces, the same z and gain).
//
// It names no physics and the effects are not chosen by it: it says how much of what is left is a
// repeatable function of the geometry and the sufferer's motion — what a missing effect would be,
// or a lab's own systematic error — and how much is not (noise, or what those inputs do not see).
#include <array>
#include <string>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

// The bumps: over the horizontal offset from 0 to the neighbour's near radius, kOffsetBumps of
// them evenly (each one spacing wide: about a jet's half-width at these separations), and over the height above at kHeightBumps points spread evenly between the near samples'
// 5th and 95th percentiles (each one spacing wide, at least kMinHeightWidth_m).
inline constexpr int kOffsetBumps = 9;
inline constexpr int kHeightBumps = 4;
inline constexpr double kMinHeightWidth_m = 0.05;
// A slow drift of the residual over the flight (a thrust map's error as the battery drains, a
// zero that wanders): bumps over time this far apart and this wide.
inline constexpr double kDriftSpacing_s = 4.0;
// The ridge penalties tried, relative to the mean diagonal of the (standardised) normal matrix;
// each axis takes the one that predicts held-out blocks best within each fold's training blocks.
inline constexpr std::array<double, 6> kRidgeGrid{1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0};

// How the report names it.
inline constexpr const char* kDiscrepancyModel =
    "ridge regression, per axis, on Gaussian bumps over each neighbour's horizontal offset and height above the "
    "sufferer (summed over the neighbours, also times the offset's direction), a constant, the sufferer's own "
    "velocity and acceleration, and bumps over the flight's time (a slow drift)";

// Fills ExplainResult::discrepancy from the final model's prediction `pred`.
Discrepancy learn_discrepancy(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds,
                              const ExplainOptions& o);

}  // namespace dw::analysis
