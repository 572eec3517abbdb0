#pragma once
// One candidate effect scored: fitted on the whole flight and screened (ΔBIC, identifiability),
// then fitted per fold of blocked cross-validation and judged on the held-out pieces (a paired
// z per axis), with intervals from the jackknife, the covariance and the tare.
#include <map>
#include <vector>

#include "analysis/explain.hpp"
#include "analysis/fit.hpp"

namespace dw::analysis {

// Blocked cross-validation: fold k holds out the blocks with block % folds == k.
struct Folds {
    std::vector<std::vector<std::size_t>> train, test;
    std::map<int, double> leg_start;  // each block's first wrench stamp (held-out pieces count from it)
};
Folds folds_of(const ExplainData& d, int folds);

// The held-out blocks are scored in pieces of this length (the residual decorrelates within ~0.1 s):
// sample i's piece (its block and the piece's index within it).
inline constexpr double kPiece_s = 0.25;
int piece_of(const ExplainData& d, const Folds& folds, std::size_t i);

// A held-out piece where the candidate predicts what the current model does — its prediction
// moves by less than this fraction of the noise (RMS) — carries no evidence either way and is
// left out of the signed-rank test (it would only dilute it).
inline constexpr double kEvidenceChange = 0.1;

// Candidate e scored against model b in forward-selection round `round`.
CandidateResult score(const ExplainData& d, const Baseline& b, const Folds& folds, Effect e, int round,
                      const ExplainOptions& o);

}  // namespace dw::analysis
