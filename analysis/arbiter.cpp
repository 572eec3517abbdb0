#include "analysis/arbiter.hpp"

#include <cmath>

#include "analysis/discrepancy.hpp"
#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

double sum(const std::map<int, AxisValues>& m, std::size_t a) {
    double s = 0;
    for (const auto& [piece, v] : m) s += v[a];
    return s;
}

// How far the model falls short on axis a of the discrepancy at its best: learnt without any effect
// (`yard`), or on top of the model (`top`: the model and it together).
ShortOfDiscrepancy shortfall(const PieceErrors& yard, const PieceErrors& top, const Discrepancy& top_fit,
                             std::size_t a) {
    const double before = sum(yard.before, a), model = sum(top.before, a);
    ShortOfDiscrepancy s{static_cast<int>(a), before > 0 ? 1 - model / before : 0, 0, top_fit.axis_t[a]};
    const double alone = before > 0 ? 1 - sum(yard.after, a) / before : 0;
    const double together = 1 - (1 - s.effect_gain) * (1 - top_fit.axis_gain[a]);
    s.discrepancy_gain = std::max(alone, together);
    return s;
}

std::string short_note(const ShortOfDiscrepancy& s) {
    const auto a = static_cast<std::size_t>(s.axis);
    return log::cat("; but it falls short of the discrepancy: with it the model removes ",
                    std::round(s.effect_gain * 1000) / 10, " % of the held-out ", kAxes[a],
                    " error, a learnt discrepancy ", std::round(s.discrepancy_gain * 1000) / 10,
                    " %, and what it leaves has structure (z = ", std::round(s.z * 10) / 10,
                    "): it stands in for part of a mismatch the vocabulary does not name — not accepted");
}

}  // namespace

Baseline arbitrate(ExplainResult& R, const ExplainData& d, const Baseline& base, const Baseline& final_model,
                   const Folds& folds, const ExplainOptions& o, const std::function<void(const std::string&)>& say,
                   bool& refused) {
    refused = false;
    if (R.accepted.empty()) return final_model;
    say("is what is left after the accepted effects modelled better by a discrepancy than by them?");
    PieceErrors yard, on_top;
    const Discrepancy top = learn_discrepancy(d, final_model.pred, folds, o, false, &on_top);
    learn_discrepancy(d, base.pred, folds, o, false, &yard);
    std::vector<CandidateResult> kept;
    for (auto& c : R.accepted) {
        const auto a = static_cast<std::size_t>(c.best_axis);
        const ShortOfDiscrepancy s = shortfall(yard, on_top, top, a);
        if (!top.significant_on(a, o.min_t, o.min_gain) || s.discrepancy_gain - s.effect_gain < o.min_gain) {
            kept.push_back(c);
            continue;
        }
        c.accepted = false;
        c.stand_in = true;
        c.short_of = s;
        c.note += short_note(s);
        say(log::cat("  ", c.effect.name, short_note(s)));
        R.candidates.push_back(c);
        refused = true;
    }
    if (!refused) return final_model;
    R.accepted = kept;
    physics::PhysicsConfig all = o.physics;
    for (const auto& c : R.accepted) c.effect.apply(all, c.values);
    return baseline_of(d, all);
}

}  // namespace dw::analysis
