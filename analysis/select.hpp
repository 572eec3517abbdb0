#pragma once
// Forward selection: rounds in which every remaining candidate is scored and the accepted one with
// the lowest held-out error that is one value for the whole flight (not a stand-in for something
// the vocabulary does not name) joins the model; then each accepted effect refitted with the others.
#include <functional>
#include <string>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

using Progress = std::function<void(const std::string&)>;

// From `candidates`: every score into R.candidates, the accepted effects into R.accepted; returns
// the final model. stand_in: the last round saw a candidate that predicts better only as a stand-in.
Baseline select_effects(ExplainResult& R, const ExplainData& d, const Baseline& base, const Folds& folds,
                        const std::vector<Effect>& candidates, const ExplainOptions& o, const Progress& say,
                        bool& stand_in);

}  // namespace dw::analysis
