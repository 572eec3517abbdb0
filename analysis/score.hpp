#pragma once
// One candidate effect scored: fitted on the whole flight and screened (ΔBIC, identifiability),
// then fitted per fold of blocked cross-validation and judged on the held-out pieces (a paired
// z per axis), with intervals from the jackknife, the covariance and the tare.
#include <map>
#include <utility>
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

// Per held-out piece (any key: a flight's piece_of, or a session's flight and piece): the
// normalised squared errors per axis before and after a change of the model, the samples, and how
// much the change moves the prediction (normalised, summed).
struct PieceScores {
    std::map<long, AxisValues> before, after;
    std::map<long, std::size_t> n;
    std::map<long, double> change;
    // Sample i of d, predicted as before_pred and after_pred, into piece `piece`.
    void add(long piece, const ExplainData& d, const std::vector<Wrench6>& before_pred,
             const std::vector<Wrench6>& after_pred, std::size_t i);
};

// The paired test over the pieces, per axis: its z (paired_z over the pieces where the change
// moves the prediction) and the fraction of its error removed; the axis judged is the most
// significant of those that gain at least min_gain (else the most significant).
struct HeldOut {
    AxisValues axis_t{}, axis_gain{};
    int best_axis = 2;
    double t = 0, gain = 0, evidence_pieces = 0;
};
HeldOut judge_pieces(const PieceScores& s, double min_gain);

// A parameter fitted to a bound that is not its neutral value has not been identified: the effect
// is standing in for something else.
inline constexpr double kPinnedFraction = 1e-4;  // of the parameter's range
bool pinned(const Effect& e, const std::vector<double>& values);

// The axes of an effect between two axes over these flights (each with the model it is scored against): the pair
// whose residual, in noise floors and summed over the flights, the other measured axis explains
// best by regression.
Effect with_crosstalk_axes(Effect e, const std::vector<std::pair<const ExplainData*, const Baseline*>>& flights);

// A cross-talk's direction: the regression that chooses its pair (with_crosstalk_axes) cannot tell
// the pair's two directions apart where one axis's measurement holds the other's (a leak from a into
// b puts a's own residual into the measured b, which then seems to explain a). Both directions are
// scored (score_one: an Effect to its result) and the one whose held-out z (held_out_z) is larger kept.
template <class ScoreOne, class HeldOutZ>
auto in_better_direction(const Effect& on_pair, ScoreOne score_one, HeldOutZ held_out_z) {
    Effect reverse = on_pair;
    std::swap(reverse.from, reverse.to);
    reverse.axes_given = true;
    auto c = score_one(on_pair);
    auto r = score_one(reverse);
    return held_out_z(r) > held_out_z(c) ? r : c;
}

// Candidate e scored against model b in forward-selection round `round`; a cross-talk whose axes
// are not given on the pair with_crosstalk_axes chooses, in_better_direction.
CandidateResult score(const ExplainData& d, const Baseline& b, const Folds& folds, Effect e, int round,
                      const ExplainOptions& o);

}  // namespace dw::analysis
