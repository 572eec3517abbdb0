#pragma once
// The discrepancy as the arbiter (issue 68). An effect of the vocabulary names what was left out;
// the learnt discrepancy (analysis/discrepancy.hpp) models what is left whatever its name. After
// forward selection, each accepted effect is judged on its axes — the one its held-out test was
// judged on, and every other where it removes at least min_gain of the held-out error (a position
// offset judged on a moment may carry much of its push on f_d). It is kept when
//   - a discrepancy fitted on top of the model with every accepted effect finds no significant
//     structure left there (the candidates' rule: held-out z ≥ min_t, ≥ min_gain of the error), or
//   - the model removes about as much of that axis's held-out error as the yardstick does — a
//     discrepancy learnt without any effect and without the effect's own linearisation (a rate of
//     change for a delay, a gain for a scale or a leak: else it would match the effect by being it) —
//     within min_gain, or
//   - the effect adds to the yardstick: the model with it and the yardstick on top predict the
//     held-out pieces better than the yardstick alone, by the candidates' rule (a real effect in a
//     flight whose physics is also wrong in shape).
// Otherwise it only stands in for part of a mismatch the vocabulary does not name: it is refused
// (its note and `short_of` give the figures), and the selection is made again without it, so that
// what the flight does show can still be named.
//
// Judged on the whole set, not candidate by candidate in its round: in a flight with two true
// effects, the first one's model leaves the second as structure, which is not a stand-in.
#include <functional>
#include <string>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

// Checks R.accepted (the model `final_model`) against the discrepancy. Refused effects leave
// R.accepted, their refused scores are appended to R.candidates, and their names returned.
std::vector<std::string> arbitrate(ExplainResult& R, const ExplainData& d, const Baseline& base,
                                   const Baseline& final_model, const Folds& folds, const ExplainOptions& o,
                                   const std::function<void(const std::string&)>& say);

}  // namespace dw::analysis
