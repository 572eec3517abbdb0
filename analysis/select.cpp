#include "analysis/select.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>
#include <set>

#include "core/log.hpp"
#include "core/stats.hpp"
#include "analysis/splits.hpp"

namespace dw::analysis {

namespace {

// Whether an effect can act in this flight (its type says: merging needs two jets, a sufferer's own
// drag and the ground effect need a sufferer that flies).
bool applies(const Effect& e, const Resimulation& r) { return e.type->applies(r.neighbours(), r.flying()); }

// An effect of the vocabulary has one value for the whole flight: fitted again on parts of the
// flight split along each axis it spans, it must keep it (analysis/splits.hpp). Checked for the
// candidate about to be accepted in each round; one that moves stands in for something the
// vocabulary does not name and is not accepted.
void stand_in_check(CandidateResult& c, const ExplainData& d, const Baseline& b) {
    c.one_value = one_value_check(d, b.physics, c.effect, c.values, b.factor);
    if (!c.one_value) return;
    c.stand_in_z = c.one_value->z;
    c.note += c.one_value->note;
    if (!c.one_value->moved) return;
    c.accepted = false;
    c.stand_in = true;
}

// Whether the held-out data cannot tell c from best: per piece, how much more error c leaves than
// best, not significantly positive.
bool cannot_tell(const CandidateResult& best, const CandidateResult& c, double min_t) {
    std::vector<double> d;
    for (const auto& [piece, err] : best.heldout_pieces)
        if (const auto it = c.heldout_pieces.find(piece); it != c.heldout_pieces.end()) d.push_back(it->second - err);
    return paired_z(d) < min_t;
}

// The other accepted candidates of a round that the held-out data cannot tell from the best one.
// (A first-order lag looks like a clock offset of about tau on forces that change slowly.)
std::vector<std::string> indistinguishable(const CandidateResult& best, const std::vector<CandidateResult>& round,
                                           double min_t) {
    std::vector<std::string> out;
    for (const auto& c : round)
        if (c.accepted && c.effect.name != best.effect.name && cannot_tell(best, c, min_t))
            out.push_back(c.effect.name);
    return out;
}

// The members of best's family scored in the round (accepted or not, but cross-validated) that the
// held-out data cannot tell from it.
std::vector<std::string> family_alike(const CandidateResult& best, const std::vector<CandidateResult>& round,
                                      double min_t) {
    std::vector<std::string> out;
    const auto* family = best.effect.type->family();
    for (const auto& c : round)
        if (family && c.effect.name != best.effect.name && c.effect.type->family() == family &&
            !c.heldout_pieces.empty() && cannot_tell(best, c, min_t))
            out.push_back(c.effect.name);
    return out;
}

// The members of best's family that passed the held-out test in its round on their own: they
// explain the same shift, less well on this flight (which member fits a flight best is not always
// its cause: a flight's own structure beside the shift can favour another member).
std::vector<std::string> family_passed(const CandidateResult& best, const std::vector<CandidateResult>& round) {
    std::vector<std::string> out;
    const auto* family = best.effect.type->family();
    for (const auto& c : round)
        if (family && c.effect.name != best.effect.name && c.effect.type->family() == family && c.accepted)
            out.push_back(c.effect.name);
    return out;
}

// One forward-selection round: every remaining candidate scored; the accepted one with the lowest
// held-out error that is one value for the whole flight (not a stand-in), if any.
struct Round {
    std::vector<CandidateResult> scored;
    std::optional<std::size_t> best;  // index into scored
    bool stand_in = false;            // a mismatch the vocabulary can only stand in for
};

Round select_round(const ExplainData& d, const Baseline& b, const Folds& folds, const std::vector<Effect>& remaining,
                   int round, const ExplainOptions& o, const Progress& say) {
    Round r;
    for (const auto& e : remaining) {
        if (!applies(e, d.sim)) continue;
        say(log::cat("round ", round, ": fitting ", e.name));
        r.scored.push_back(score(d, b, folds, e, round, o));
        say(log::cat("  ", r.scored.back().note));
    }
    std::vector<std::size_t> ranked;
    for (std::size_t k = 0; k < r.scored.size(); ++k)
        if (r.scored[k].accepted) ranked.push_back(k);
    std::sort(ranked.begin(), ranked.end(),
              [&](std::size_t x, std::size_t y) { return r.scored[x].total_ratio < r.scored[y].total_ratio; });
    for (auto k : ranked) {
        say(log::cat("  is ", r.scored[k].effect.name, " one value for the whole flight?"));
        stand_in_check(r.scored[k], d, b);
        if (r.scored[k].accepted) {
            r.best = k;
            break;
        }
    }
    r.stand_in = std::any_of(r.scored.begin(), r.scored.end(), [](const CandidateResult& c) { return c.stand_in; });
    return r;
}

// With several effects, each one's parameters refitted with the others in place.
void refit_together(ExplainResult& R, const ExplainData& d, const Folds& folds, const ExplainOptions& o,
                    const Progress& say) {
    for (std::size_t k = 0; k < R.accepted.size(); ++k) {
        physics::PhysicsConfig others = o.physics;
        for (std::size_t j = 0; j < R.accepted.size(); ++j)
            if (j != k) R.accepted[j].effect.apply(others, R.accepted[j].values);
        say(log::cat("refitting ", R.accepted[k].effect.name, " with the other effects in place"));
        auto again = score(d, baseline_of(d, others), folds, R.accepted[k].effect, R.accepted[k].round, o);
        if (again.accepted) {
            again.heldout_before = R.accepted[k].heldout_before;
            again.indistinguishable = R.accepted[k].indistinguishable;
            again.family_alike = R.accepted[k].family_alike;
            again.family_passed = R.accepted[k].family_passed;
            again.stand_in_z = R.accepted[k].stand_in_z;  // checked in its round, not again
            again.one_value = R.accepted[k].one_value;
            if (again.one_value) again.note += again.one_value->note;
            R.accepted[k] = again;
        }
    }
}

}  // namespace

// Forward selection from the base model: rounds until nothing more is accepted; returns the final model.
Baseline select_effects(ExplainResult& R, const ExplainData& d, const Baseline& base, const Folds& folds,
                        const std::vector<Effect>& candidates, const ExplainOptions& o, const Progress& say,
                        bool& stand_in) {
    Baseline current = base;
    std::vector<Effect> remaining = candidates;
    stand_in = false;
    for (int round = 1; round <= o.max_effects && !remaining.empty(); ++round) {
        Round r = select_round(d, current, folds, remaining, round, o, say);
        R.candidates.insert(R.candidates.end(), r.scored.begin(), r.scored.end());
        stand_in = r.stand_in;
        if (!r.best) break;
        const CandidateResult& best = r.scored[*r.best];
        R.accepted.push_back(best);
        R.accepted.back().indistinguishable = indistinguishable(best, r.scored, o.min_t);
        R.accepted.back().family_alike = family_alike(best, r.scored, o.min_t);
        R.accepted.back().family_passed = family_passed(best, r.scored);
        physics::PhysicsConfig next = current.physics;
        best.effect.apply(next, best.values);
        current = baseline_of(d, next);
        std::erase_if(remaining, [&](const Effect& e) { return e.name == best.effect.name; });
        R.heldout_before = R.accepted.front().heldout_before;
        R.heldout_after = best.heldout_after;
    }
    if (R.accepted.size() > 1) {
        refit_together(R, d, folds, o, say);
        physics::PhysicsConfig all = o.physics;
        for (const auto& c : R.accepted) c.effect.apply(all, c.values);
        current = baseline_of(d, all);
    }
    return current;
}

}  // namespace dw::analysis
