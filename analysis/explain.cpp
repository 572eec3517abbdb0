#include "analysis/explain.hpp"

#include <glog/logging.h>

#include <chrono>
#include <mutex>
#include <set>

#include "analysis/arbiter.hpp"
#include "analysis/discrepancy.hpp"
#include "analysis/fit.hpp"
#include "analysis/locate.hpp"
#include "analysis/noise.hpp"
#include "analysis/score.hpp"
#include "analysis/select.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "physics/bodies.hpp"

namespace dw::analysis {

namespace {

// ---- explain(), stage by stage: resimulate -> locate -> screen -> cross-validate -> select -> report

// The verdict: what the fit leaves, whether a mismatch is detected and whether it is explained.
void conclude(ExplainResult& R, const ExplainData& d, const Baseline& base, const Baseline& final_model, bool stand_in,
              const ExplainOptions& o, const std::string& formation) {
    const std::vector<Wrench6>& base_pred = base.pred;
    if (R.accepted.empty()) R.heldout_before = R.heldout_after = residual_rms(d, base_pred);
    R.fitted = final_model.physics;
    const auto noise = physics::prediction_noise_of(o.physics);
    const PushNoise before(d, base_pred, noise), after(d, final_model.pred, noise);  // each pred's rates once
    R.excess_before = excess_of(d, before);
    R.excess_after = excess_of(d, after);
    // Whether: an accepted effect, a candidate that predicts held-out data better but only as a
    // stand-in, or a residual beyond what noise and turbulence explain (the regions say where; on
    // their own they are many cells tested at once, not evidence).
    const bool excess = largest(R.excess_before) > o.detect_excess;
    R.line_before = strongest_line(d, before);
    R.line_after = R.line_before.significant ? strongest_line(d, after) : R.line_before;
    const bool any_stand_in =
        std::any_of(R.candidates.begin(), R.candidates.end(), [](const CandidateResult& c) { return c.stand_in; });
    R.detected = !R.accepted.empty() || excess || any_stand_in || R.line_before.significant;
    if (R.detected && R.regions.empty())  // found by its size or a stand-in: say where, with the weaker threshold
        R.regions = locate(d, base_pred, base.factor, o.weak_region_z, formation);
    R.unexplained = largest(R.excess_after) > o.detect_excess || stand_in || R.line_after.significant;
}

// The time shift that best aligns recording and simulation over the flight: the shift table's
// median, weighted by samples.
double located_shift(const std::vector<Shift>& shifts) {
    std::vector<Shift> v = shifts;
    std::sort(v.begin(), v.end(), [](const Shift& a, const Shift& b) { return a.shift_s < b.shift_s; });
    std::size_t total = 0, run = 0;
    for (const auto& x : v) total += x.samples;
    for (const auto& x : v)
        if ((run += x.samples) * 2 >= total) return x.shift_s;
    return 0;
}

// The candidates, each family member's grid of starting points joined by its reading of the
// family's quantity (the delay family's: the located shift), so that every member's fit can
// converge from the family's best shift whatever its own grid.
std::vector<Effect> with_family_starts(std::vector<Effect> candidates, double shift_s) {
    for (auto& e : candidates) {
        const auto v = e.type->family() ? e.type->from_family_quantity(shift_s) : std::nullopt;
        if (!v || v->size() != 1 || e.params.size() != 1) continue;
        e.params[0].grid.push_back(std::clamp((*v)[0], e.params[0].fit_min, e.params[0].fit_max));
    }
    return candidates;
}

// Forward selection, then the arbiter; an effect it refuses is left out and the selection made again
// (each refusal removes a candidate, so this ends). stand_in: a stand-in was seen on the way.
Baseline select_and_arbitrate(ExplainResult& R, const ExplainData& d, const Baseline& base, const Folds& folds,
                              const ExplainOptions& o, const Progress& say, bool& stand_in) {
    std::vector<Effect> candidates = with_family_starts(o.candidates, located_shift(R.shifts));
    bool any_refused = false;
    for (;;) {
        R.accepted.clear();
        const Baseline selected = select_effects(R, d, base, folds, candidates, o, say, stand_in);
        const auto refused = arbitrate(R, d, base, selected, folds, o, say);
        if (refused.empty()) {
            stand_in = stand_in || any_refused;
            return selected;
        }
        any_refused = true;
        std::erase_if(candidates, [&](const Effect& e) {
            return std::find(refused.begin(), refused.end(), e.name) != refused.end();
        });
        say(log::cat("selecting again without ", log::join(refused)));
    }
}

// The members of c's family that the flight also supports: those the held-out data cannot tell
// from it in its round, and those that passed the held-out test anywhere in the explanation but were
// refused as stand-ins (their value moved across the flight, or they fell short of the
// discrepancy) — they explain the same shift in another way. Once the flight is shown unable to
// separate some members, those that passed the held-out test in c's round join them ("less well").
struct Supported {
    std::vector<std::string> alike, less_well;
};
Supported also_supported(const ExplainResult& R, const CandidateResult& c) {
    Supported out{c.family_alike, {}};
    const auto* family = c.effect.type->family();
    const auto listed = [&](const std::string& n) {
        return std::find(out.alike.begin(), out.alike.end(), n) != out.alike.end() ||
               std::find(out.less_well.begin(), out.less_well.end(), n) != out.less_well.end();
    };
    for (const auto& m : R.candidates)
        if (family && m.effect.type->family() == family && m.effect.name != c.effect.name && m.stand_in &&
            !listed(m.effect.name))
            out.alike.push_back(m.effect.name);
    if (out.alike.empty()) return out;
    for (const auto& n : c.family_passed)
        if (!listed(n)) out.less_well.push_back(n);
    return out;
}

// The push of the accepted model as a multiple of the plain model's: the least-squares ratio over the
// samples on legs, in noise floors.
double push_multiple(const ExplainData& d, const std::vector<Wrench6>& plain, const std::vector<Wrench6>& with) {
    double xy = 0, xx = 0;
    for (auto i : d.on_legs)
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            const double x = plain[i][a] / d.sigma[a], y = with[i][a] / d.sigma[a];
            xy += x * y, xx += x * x;
        }
    return xx > 0 ? xy / xx : 1.0;
}

// The other members of c's family that this flight cannot be told from c by its design: an accepted
// gain of the whole push, on a flight where jets share the push wherever it is measured, is any
// member of its family that acts on the flight (how jets combine shows the same there).
std::vector<std::string> unseparated_by_design(const ExplainResult& R, const CandidateResult& c,
                                               const Resimulation& sim) {
    std::vector<std::string> out;
    if (!c.effect.type->gain_of_the_push() || sim.neighbours() < 2 || R.one_jet.measured == 0 || R.one_jet.enough())
        return out;
    for (const auto* t : physics::effect_types())
        if (t != c.effect.type && t->family() == c.effect.type->family() && t->applies(sim.neighbours(), sim.flying()))
            out.push_back(t->name());
    return out;
}

std::string by_design_words(const OneJetPart& j) {
    return log::cat(": jets share the push wherever it is measured (one jet alone in ", j.alone, " of ", j.measured,
                    " samples, fewer than the ", kMinPartSamples, " a split needs; the others carry ",
                    fixed(j.median_share * 100, 0),
                    " % of it at the median), and a gain of the whole push shows "
                    "alone only where one jet pushes alone: fly one neighbour alone over the stand to separate them");
}

// Accepted effects that the flight cannot tell from other members of their family: the family named,
// with what its members share (the delay family: the located shift; the push family: the gain's value,
// or push_multiple when another member is kept).
std::vector<FamilyVerdict> families_of(const ExplainResult& R, const Resimulation& sim, double push) {
    std::vector<FamilyVerdict> out;
    for (const auto& c : R.accepted) {
        auto others = also_supported(R, c);
        const auto by_design = unseparated_by_design(R, c, sim);
        for (const auto& n : by_design)
            if (std::find(others.alike.begin(), others.alike.end(), n) == others.alike.end()) others.alike.push_back(n);
        if (others.alike.empty()) continue;
        const auto* family = c.effect.type->family();
        const double gain = c.effect.type->gain_of_the_push() ? c.values.at(0) : push;
        FamilyVerdict v{family, {c.effect.name}, family == &physics::kPushFamily ? gain : located_shift(R.shifts), {}};
        v.members.insert(v.members.end(), others.alike.begin(), others.alike.end());
        const std::vector<std::string> first(v.members.begin(), v.members.end() - 1);
        const std::string less_well =
            others.less_well.empty()
                ? ""
                : log::cat(" (", log::join(others.less_well), " also passed the held-out test: it explains the shift ",
                           "less well here)");
        v.members.insert(v.members.end(), others.less_well.begin(), others.less_well.end());
        const std::string why = by_design.empty() ? "" : by_design_words(R.one_jet);
        const std::string kept = by_design.empty() ? " is kept for its lower held-out error"
                                                   : " is kept as the family's reading (it passed the held-out test)";
        v.sentence = log::cat(family->shared, " of ", std::round(v.shared_value * 1000) / 1000, family->unit, ": ",
                              log::join(first), " or ", v.members[first.size()], " — this flight cannot tell which",
                              why, "; ", c.effect.name, kept, less_well);
        out.push_back(std::move(v));
    }
    return out;
}

// The held-out variance shared out on f_d (else the axis with the largest held-out error).
VarianceShares shares_of(const ExplainResult& R, const ExplainData& d, const std::vector<Wrench6>& pred,
                         const physics::PredictionNoise& model) {
    VarianceShares v;
    v.axis = d.sim.measured_axes()[2]
                 ? 2
                 : static_cast<int>(std::max_element(R.heldout_before.begin(), R.heldout_before.end()) -
                                    R.heldout_before.begin());
    const auto a = static_cast<std::size_t>(v.axis);
    const auto sq = [](double x) { return x * x; };
    double turbulent = 0;
    const PushNoise push(d, pred, model);
    for (auto i : d.on_legs) turbulent += turbulent_variance(d, push, i, a);
    turbulent /= static_cast<double>(std::max<std::size_t>(1, d.on_legs.size()));
    const double before = sq(R.heldout_before[a]), after = sq(R.heldout_after[a]);
    const double left = R.discrepancy.significant ? std::min(after, sq(R.discrepancy.heldout_after[a])) : after;
    // What is left is the noise floor's first (measured where nobody is near), then the turbulence's
    // up to what the model expects of it, then unexplained.
    const double noise = sq(d.sigma[a]), expected = noise + turbulent;
    v.effects = std::max(0.0, before - after);
    v.discrepancy = std::max(0.0, after - left);
    v.noise = std::min(left, noise);
    v.turbulence = std::min(left - v.noise, turbulent);
    v.unexplained = left - v.noise - v.turbulence;
    v.total = v.effects + v.discrepancy + v.noise + v.turbulence + v.unexplained;
    for (double* x : {&v.effects, &v.discrepancy, &v.noise, &v.turbulence, &v.unexplained})
        *x = v.total > 0 ? *x / v.total : 0;
    // Noise is what nothing predicts: where the learnt discrepancy predicts held-out data, what the
    // physics leaves has structure, whatever its size.
    const double within = kDetectExcess * kDetectExcess * expected;
    v.to_the_noise = after <= within && !R.discrepancy.significant;
    v.modelled_to_the_noise = !v.to_the_noise && R.discrepancy.significant && left <= within;
    return v;
}

}  // namespace

void validate(const ExplainOptions& o) {
    require_in(o.folds, kFoldsRange, "explain: folds");
    require_in(o.max_delta_bic, kDeltaBicRange, "explain: max_delta_bic");
    require_in(o.min_t, kZRange, "explain: min_t");
    require_in(o.min_gain, kGainRange, "explain: min_gain");
    require_in(o.region_z, kZRange, "explain: region_z");
    require_in(o.weak_region_z, kZRange, "explain: weak_region_z");
    require_in(o.detect_excess, kExcessRange, "explain: detect_excess");
    require_in(o.max_effects, kMaxEffectsRange, "explain: max_effects");
    require_in(o.huber_delta, kHuberRange, "explain: huber_delta");
    require_in(o.shift_half_width_s, kShiftHalfWidthRange, "explain: shift_half_width_s");
    require_in(o.shift_step_s, kShiftStepRange, "explain: shift_step_s");
    if (o.shift_step_s > o.shift_half_width_s)
        throw InputError(log::cat("explain: shift_step_s ", o.shift_step_s, " is wider than shift_half_width_s ",
                                  o.shift_half_width_s));
}

std::string verdict_line(const ExplainResult& r) {
    std::string by;
    for (const auto& c : r.accepted) by += (by.empty() ? "" : ", ") + c.effect.name;
    if (!r.detected) return "no mismatch";
    if (by.empty()) return "mismatch found, not explained";
    for (const auto& v : r.families) by += "; " + v.sentence;
    return "explained by: " + by + (r.unexplained ? " (a residual remains unexplained)" : "");
}

// The held-out variance shared out, in one line.
std::string shares_line(const VarianceShares& v) {
    const auto pc = [](double x) { return fixed(100 * x, 0) + " %"; };
    return log::cat("Of the held-out ", flight::kAxes[static_cast<std::size_t>(v.axis)], " variance (",
                    fixed(std::sqrt(v.total), 4), " RMS): noise ", pc(v.noise), ", turbulence ", pc(v.turbulence),
                    ", the accepted effects ", pc(v.effects), ", the learnt discrepancy ", pc(v.discrepancy),
                    ", unexplained ", pc(v.unexplained),
                    v.to_the_noise            ? " — explained to the noise"
                    : v.modelled_to_the_noise ? " — not explained to the noise by physics; the learnt discrepancy "
                                                "models what is left to the noise"
                                              : "",
                    ".\n\n");
}

std::string turbulence_line(const ExplainResult& r, double physics_intensity) {
    if (r.turbulence.empty()) return "";
    std::vector<std::string> bands, beyond;
    for (const auto& b : r.turbulence) {
        const std::string at = log::cat(fixed(b.intensity, 2), " at ", kBands[b.band].name, " below the neighbour");
        bands.push_back(log::cat(at, " (", b.samples, " samples)"));
        if (b.intensity > kTurbulenceBeyond * physics_intensity) beyond.push_back(at);
    }
    return log::cat("Near a jet the residual scatters with the push as turbulence of intensity ", log::join(bands),
                    " — if the mean flow is right there; the physics' noise model counts ", fixed(physics_intensity, 2),
                    beyond.empty() ? "." : log::cat(". **Left out: turbulence, intensity ", log::join(beyond), ".**"),
                    "\n\n");
}

ExplainResult explain(const flight::Flight& f, const ExplainOptions& o) {
    validate(o);
    // Ceres warns on stderr when a covariance is rank deficient (a parameter the rows cannot see:
    // a group of passes where the effect does not act); its standard error is then infinite here,
    // which is what that means. Set once for the process, not per call.
    static std::once_flag quiet_ceres;
    std::call_once(quiet_ceres, [] { FLAGS_minloglevel = google::GLOG_ERROR; });
    const auto started = std::chrono::steady_clock::now();
    const Progress say = [&](const std::string& s) {
        if (o.progress) o.progress(s);
    };
    ExplainResult R;
    R.formation = f.meta.formation;
    if (!o.physics.discrepancy.empty()) say("the configuration's learnt discrepancy is not used: this explains anew");
    // Resimulation.
    const Resimulation sim(f, o.physics);
    const auto blocks = flight::find_blocks(f, o.folds, physics::encounter_radii(f.meta, o.physics));
    R.blocks = blocks.kind;
    if (blocks.blocks.size() < static_cast<std::size_t>(o.folds))
        throw InputError(log::cat("poses.csv: ", blocks.blocks.size(), " cross-validation blocks (",
                                  flight::to_string(blocks.kind), ") in the flight; cross-validation needs at least ",
                                  o.folds));
    const auto info = describe(sim, blocks, o.physics);
    say(log::cat("simulating the recorded flight: ", sim.stamps().size(), " wrench samples, ", sim.neighbours(),
                 " neighbours, ", blocks.blocks.size(), " blocks by ", flight::to_string(blocks.kind)));
    auto base_pred = sim.recorded(o.physics);
    const NoiseFloor floor = floor_of(sim, info, base_pred, o.physics.stand.tare_s);
    const ExplainData d = explain_data(sim, info, blocks, o.folds, o.huber_delta, o.physics, floor.sigma);
    const Baseline base = baseline_of(d, o.physics, std::move(base_pred));
    R.noise_floor = d.sigma;
    R.noise_floor_basis = floor.basis;
    R.samples = d.on_legs.size();
    R.legs = d.legs;
    // Locate.
    R.regions = locate(d, base.pred, base.factor, o.region_z, f.meta.formation);
    R.shifts = shifts(d, o.physics, o);
    say(log::cat(R.regions.size(), " significant regions; effective samples ", base.factor * 100,
                 " % of the samples (autocorrelation)"));
    // Screen, cross-validate and select; then the verdict.
    bool stand_in = false;
    const Folds folds = folds_of(d, o.folds);
    const Baseline final_model = select_and_arbitrate(R, d, base, folds, o, say, stand_in);
    conclude(R, d, base, final_model, stand_in, o, f.meta.formation);
    if (sim.neighbours() >= 2) R.one_jet = one_jet_part(d, final_model.pred);
    R.families = families_of(R, sim, push_multiple(d, base.pred, final_model.pred));
    say("learning what is left as a function of the geometry");
    physics::LearntDiscrepancy model;
    DiscrepancyRun run;
    run.model = &model;
    R.discrepancy = learn_discrepancy(d, final_model.pred, folds, o, run);
    say(log::cat("  ", R.discrepancy.note));
    R.fitted.discrepancy.clear();     // the explainer learns its own, never uses one it is given
    if (R.discrepancy.significant) {  // repeatable: the fitted physics carries it (dw-sim replay applies it)
        model.flight = log::cat("a ", f.meta.formation, " flight of ", f.wrench.size(), " wrench samples");
        R.fitted.discrepancy.push_back(std::move(model));
    }
    if (R.discrepancy.structured) {  // detection by structure: what is left has a shape
        R.detected = R.unexplained = true;
        say(log::cat("  what is left has a shape: it depends on ", R.discrepancy.structured_by,
                     " beyond every other input"));
    }
    R.shares = shares_of(R, d, final_model.pred, physics::prediction_noise_of(o.physics));
    R.turbulence = turbulence_by_band(d, final_model.pred, static_cast<std::size_t>(R.shares.axis));
    R.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    R.resimulations = d.resimulations + 1;  // and the base model's, before the data
    say(log::cat("done: ", R.resimulations, " resimulations of the flight in ", std::round(R.seconds * 10) / 10, " s"));
    return R;
}

}  // namespace dw::analysis
