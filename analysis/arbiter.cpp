#include "analysis/arbiter.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>

#include "analysis/discrepancy.hpp"
#include "physics/effect_types.hpp"
#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

// The inputs of the discrepancy that are effect e's own linearisation, which its yardstick leaves
// out — else the discrepancy would match e by being it: a rate of change for the delay family, a
// gain for the effects at the stand's calibration (a scale, a leak).
std::vector<InputGroup> own_linearisation(const Effect& e) {
    std::vector<InputGroup> out;
    if (e.type->family() == &physics::kDelayFamily) out.push_back(InputGroup::rate);
    if (e.type->stage() == physics::Stage::calibration) out.push_back(InputGroup::gain);
    return out;
}

// On axis a: what the model removes of the held-out error, what the yardstick learnt without any
// effect removes (`yard`), and what the model and the yardstick on top of it remove together
// (`on_top`); z: the evidence, piece by piece, that the last beats the second.
ShortOfDiscrepancy compare(const PieceErrors& yard, const PieceErrors& on_top, std::size_t a) {
    const double before = total(yard.before, a);
    ShortOfDiscrepancy s{static_cast<int>(a)};
    if (!(before > 0)) return s;
    s.effect_gain = 1 - total(on_top.before, a) / before;
    s.discrepancy_gain = 1 - total(yard.after, a) / before;
    s.together_gain = 1 - total(on_top.after, a) / before;
    std::vector<double> d;
    for (const auto& [piece, after] : yard.after)
        d.push_back((after[a] - on_top.after.at(piece)[a]) / static_cast<double>(yard.n.at(piece)));
    s.z = paired_z(d);
    return s;
}

// The first of c's axes where it falls short (arbiter.hpp: structure left, less than the yardstick
// alone removes, and nothing significant added to it), with the figures.
std::optional<ShortOfDiscrepancy> short_on_an_axis(const CandidateResult& c, const PieceErrors& yard,
                                                   const PieceErrors& on_top, const Discrepancy& top,
                                                   const ExplainOptions& o) {
    for (std::size_t a = 0; a < 6; ++a) {
        if (static_cast<int>(a) != c.best_axis && c.axis_gain[a] < o.min_gain) continue;
        if (!top.significant_on(a, o.min_t, o.min_gain)) continue;
        const ShortOfDiscrepancy s = compare(yard, on_top, a);
        const bool about_as_much = s.discrepancy_gain - s.effect_gain < o.min_gain;
        const bool adds = s.z >= o.min_t && s.together_gain - s.discrepancy_gain >= o.min_gain;
        if (!about_as_much && !adds) return s;
    }
    return std::nullopt;
}

std::string short_note(const ShortOfDiscrepancy& s) {
    const auto pc = [](double x) { return std::round(x * 1000) / 10; };
    return log::cat("; but it falls short of the discrepancy: on ", kAxes[static_cast<std::size_t>(s.axis)],
                    " (held-out error weighed by the noise) the model with it removes ", pc(s.effect_gain),
                    " % and leaves structure; a discrepancy learnt without any effect (and without the effect's own "
                    "linearisation) removes ",
                    pc(s.discrepancy_gain), " %, and with the effect under it ", pc(s.together_gain),
                    " % (z = ", std::round(s.z * 10) / 10,
                    "): it stands in for part of a mismatch the vocabulary does not name — not accepted");
}

}  // namespace

std::vector<std::string> arbitrate(ExplainResult& R, const ExplainData& d, const Baseline& base,
                                   const Baseline& final_model, const Folds& folds, const ExplainOptions& o,
                                   const std::function<void(const std::string&)>& say) {
    std::vector<std::string> refused;
    if (R.accepted.empty()) return refused;
    say("are the accepted effects more than a learnt discrepancy would model?");
    const Discrepancy top = learn_discrepancy(d, final_model.pred, folds, o, {.explain_dependence = false});
    std::vector<CandidateResult> kept;
    for (auto& c : R.accepted) {
        // Both weighed by the base model's push, so that their errors compare.
        const auto without = own_linearisation(c.effect);
        PieceErrors yard, on_top;
        learn_discrepancy(d, base.pred, folds, o, {false, without, &yard, &base.pred});
        learn_discrepancy(d, final_model.pred, folds, o, {false, without, &on_top, &base.pred});
        const auto s = short_on_an_axis(c, yard, on_top, top, o);
        if (!s) {
            kept.push_back(c);
            continue;
        }
        c.accepted = false;
        c.stand_in = true;
        c.short_of = s;
        c.note += short_note(*s);
        say(log::cat("  ", c.effect.name, short_note(*s)));
        R.candidates.push_back(c);
        refused.push_back(c.effect.name);
    }
    R.accepted = kept;
    return refused;
}

}  // namespace dw::analysis
