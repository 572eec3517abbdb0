#pragma once
// The discrepancy as the arbiter (issue 68). An effect of the vocabulary names what was left out;
// the learnt discrepancy (analysis/discrepancy.hpp) models what is left whatever its name. A named
// effect is kept only when the discrepancy fitted on top of the model with it finds no significant
// structure left on the effect's axis, or when it removes about as much of that axis's held-out
// error as a discrepancy learnt without any effect does on the same pieces — that is, when such a
// discrepancy would not itself pass the candidates' rule against the model (z ≥ min_t over the
// held-out pieces and at least min_gain of the axis's error). Otherwise the effect only stands in
// for part of a mismatch the vocabulary does not name: it is refused, and the report says by how
// much it fell short.
#include <functional>
#include <string>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

// Checks R.accepted against the discrepancy; refused effects leave R.accepted (their refused score
// is appended to R.candidates) and `refused` is set. Returns the model of the effects kept.
Baseline arbitrate(ExplainResult& R, const ExplainData& d, const Baseline& base, const Baseline& final_model,
                   const Folds& folds, const ExplainOptions& o, const std::function<void(const std::string&)>& say,
                   bool& refused);

}  // namespace dw::analysis
