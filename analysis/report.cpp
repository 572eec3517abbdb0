// report.json (downwash-explain/1), report.md, physics.yaml and the figures.
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "analysis/noise.hpp"
#include "analysis/discrepancy.hpp"
#include "analysis/explain.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "physics/effect_types.hpp"
#include "plot/chart.hpp"
#include "plot/field_map.hpp"

namespace dw::analysis {

namespace {

using nlohmann::json;
namespace fs = std::filesystem;
using flight::kAxes;  // the axes as in wrench.csv

json axes_json(const AxisValues& v) {
    json j = json::object();
    for (std::size_t a = 0; a < 6; ++a) j[kAxes[a]] = v[a];
    return j;
}

json params_json(const CandidateResult& c, bool ci) {
    json j = json::object();
    const auto& e = c.effect;
    auto val = [&](std::size_t k) { return ci ? json::array({c.lo[k], c.hi[k]}) : json(c.values[k]); };
    if (const std::string key = e.type->grouped_key(); !key.empty()) {
        json all = json::array();
        for (std::size_t k = 0; k < e.params.size(); ++k) all.push_back(val(k));
        j[key] = all;
    } else {
        if (e.type->has_axes() && !ci) {
            j["from"] = kAxes[static_cast<std::size_t>(e.from)];
            j["to"] = kAxes[static_cast<std::size_t>(e.to)];
        }
        for (std::size_t k = 0; k < e.params.size(); ++k) j[e.params[k].name] = val(k);
    }
    return j;
}

std::string params_text(const CandidateResult& c) {
    std::ostringstream s;
    for (std::size_t k = 0; k < c.values.size(); ++k) {
        if (k) s << ", ";
        s << c.effect.params[k].name << " = " << fixed(c.values[k], 4) << " [" << fixed(c.lo[k], 4) << ", "
          << fixed(c.hi[k], 4) << "]";
    }
    if (c.effect.type->has_axes()) s << " (" << kAxes[c.effect.from] << " → " << kAxes[c.effect.to] << ")";
    return s.str();
}

// What the held-out data cannot tell an accepted effect from, said beside it.
std::string alternatives(const CandidateResult& c) {
    if (c.indistinguishable.empty()) return "";
    return log::cat(" *Not distinguishable on this flight from ", log::join(c.indistinguishable, " or "),
                    "*: it was accepted too, and on the held-out blocks neither fits ", "significantly better. ",
                    c.effect.name,
                    " is kept for its lower held-out error; a flight with faster changes would tell them apart.");
}

// Who measured the force, in the report's words: a load stand, or a flying sufferer's estimate.
physics::EffectVoice voice_of(const Resimulation& r) {
    if (!r.flying())
        return {false, "the stand", "the stand's clock",
                "along each leg — towards the travel on one leg, against it on the next"};
    return {true, "the sufferer's force estimate", "the sufferer's force log",
            "along the neighbour's path — towards its travel"};
}

std::string paragraph(const CandidateResult& c, const physics::EffectVoice& who) {
    const auto axis = static_cast<std::size_t>(c.best_axis);
    const std::string err = log::cat("Held-out RMSE on ", kAxes[axis], ": ", fixed(c.heldout_before[axis], 3), " → ",
                                     fixed(c.heldout_after[axis], 3), " (", fixed(c.gain * 100, 0),
                                     " % of its squared error removed on blocks the fit never saw).");
    return c.effect.type->describe(c.values, {c.effect.from, c.effect.to}, who) + err;
}

// Mean of per-sample values binned over the formation's N-E position (0.1 m cells), for samples
// on legs in one band and leg direction (0: both).
plot::Field binned(const std::vector<double>& value, const std::vector<SampleInfo>& info, const Band& band, int dir,
                   const std::string& title) {
    plot::Field f{title, 1.2, 25, {}};
    std::vector<double> sum(625, 0), n(625, 0);
    for (std::size_t i = 0; i < value.size(); ++i) {
        const auto& w = info[i];
        if (w.leg < 0 || w.direction == 0 || w.h < band.lo || w.h >= band.hi || (dir != 0 && w.direction != dir))
            continue;
        const int in = static_cast<int>(std::lround((w.n + 1.2) / 0.1)),
                  ie = static_cast<int>(std::lround((w.e + 1.2) / 0.1));
        if (in < 0 || ie < 0 || in >= 25 || ie >= 25) continue;
        sum[static_cast<std::size_t>(in * 25 + ie)] += value[i];
        n[static_cast<std::size_t>(in * 25 + ie)] += 1;
    }
    f.v.resize(625);
    for (std::size_t k = 0; k < 625; ++k) f.v[k] = n[k] > 0 ? sum[k] / n[k] : NAN;
    return f;
}

// What the figures are drawn from: the resimulation, where each sample is, the simulation before and
// after the fit, the axis shown, and the output folder.
struct Figures {
    const Resimulation& sim;
    std::vector<SampleInfo> info;
    std::vector<Wrench6> before, after;
    std::size_t axis;
    std::string dir;
    std::string unit() const { return log::cat(kAxes[axis], axis < 3 ? " [N]" : " [N m]"); }
    std::string path(const char* name) const { return (fs::path(dir) / name).string(); }
};

// Over a stand: residual maps over the neighbours' centre by band and leg direction, and recorded
// vs simulated maps at the strongest region's band. Returns the Markdown that shows them.
std::string stand_figures(const Figures& g, const ExplainResult& r) {
    const std::size_t n = g.info.size(), axis = g.axis;
    std::vector<double> rb(n), ra(n), obs(n), sb(n), sa(n);
    for (std::size_t i = 0; i < n; ++i) {
        obs[i] = g.sim.measured()[i][axis];
        sb[i] = g.before[i][axis];
        sa[i] = g.after[i][axis];
        rb[i] = obs[i] - sb[i];
        ra[i] = obs[i] - sa[i];
    }
    const std::string unit = g.unit();
    std::vector<plot::Outline> outline{{0, 0, 0.19, true}};
    for (int which = 0; which < 2; ++which) {
        std::vector<plot::Field> fields;
        for (int way : {1, -1})
            for (const auto& band : kBands)
                fields.push_back(binned(which ? ra : rb, g.info, band, way,
                                        log::cat(band.name, way > 0 ? ", +E legs" : ", -E legs")));
        plot::render_fields(fields,
                            log::cat("residual (recorded - simulated) ", which ? "AFTER" : "BEFORE", " the fit: ", unit,
                                     " over the neighbours' centre, by altitude band and leg direction"),
                            unit, outline, g.path(which ? "residuals_after.png" : "residuals_before.png"));
    }
    // The band of the strongest region (else the top band).
    const Band& b0 =
        kBands[static_cast<std::size_t>(r.regions.empty() ? 2 : band_index(r.regions.front().altitude_lo))];
    for (int way : {1, -1}) {
        std::vector<plot::Field> fields{binned(obs, g.info, b0, way, "recorded"),
                                        binned(sb, g.info, b0, way, "simulated before"),
                                        binned(sa, g.info, b0, way, "simulated after")};
        plot::render_fields(fields,
                            log::cat(unit, " at ", b0.name, ", ", way > 0 ? "+E" : "-E",
                                     " legs: recorded vs simulated, before and after the fit"),
                            unit, outline, g.path(way > 0 ? "maps_east.png" : "maps_west.png"));
    }
    return log::cat("Residuals before and after (", unit,
                    "):\n\n![before](residuals_before.png)\n\n![after](residuals_after.png)\n\n",
                    "Recorded vs simulated at ", b0.name,
                    ":\n\n![+E legs](maps_east.png)\n\n![-E legs](maps_west.png)\n\n");
}

// A flying sufferer: the residual against the nearest neighbour's position relative to it
// (horizontal offset x height above), before and after; and recorded vs simulated along the
// flight with the cross-validation blocks marked.
std::string flying_figures(const Figures& g, const flight::Blocks& blocks) {
    constexpr double kCell = 0.05;
    const std::size_t axis = g.axis;
    std::vector<std::array<double, 3>> before, after;
    double off = kCell, lo = 0, hi = kCell;
    for (std::size_t i = 0; i < g.info.size(); ++i) {
        const auto& s = g.info[i];
        if (!std::isfinite(s.offset)) continue;
        const double m = g.sim.measured()[i][axis];
        before.push_back({s.offset, s.above, m - g.before[i][axis]});
        after.push_back({s.offset, s.above, m - g.after[i][axis]});
        off = std::max(off, s.offset), lo = std::min(lo, s.above), hi = std::max(hi, s.above);
    }
    off = std::ceil(off / kCell) * kCell, lo = std::floor(lo / kCell) * kCell, hi = std::ceil(hi / kCell) * kCell;
    const int nx = std::max(1, static_cast<int>(std::lround(off / kCell))),
              ny = std::max(1, static_cast<int>(std::lround((hi - lo) / kCell)));
    const std::string unit = g.unit();
    plot::render_heats({plot::bin_heat("before the fit", before, 0, off, lo, hi, nx, ny),
                        plot::bin_heat("after the fit", after, 0, off, lo, hi, nx, ny)},
                       log::cat("residual (recorded - simulated) ", unit, " by where the nearest neighbour is"),
                       "horizontal offset [m]", "height above the sufferer [m]", unit,
                       g.path("residual_vs_position.png"));
    plot::Chart c{log::cat(unit, " of the sufferer: recorded vs simulated; grey lines: cross-validation blocks (",
                           flight::to_string(blocks.kind), ")"),
                  "time [s]",
                  unit,
                  {},
                  {}};
    plot::Series rec{"recorded", g.sim.stamps(), {}, {40, 40, 40}},
        sb{"simulated before the fit", g.sim.stamps(), {}, {200, 120, 30}},
        sa{"simulated after the fit", g.sim.stamps(), {}, {30, 30, 210}};
    for (std::size_t i = 0; i < g.info.size(); ++i) {
        rec.y.push_back(g.sim.measured()[i][axis]);
        sb.y.push_back(g.before[i][axis]);
        sa.y.push_back(g.after[i][axis]);
    }
    c.series = {rec, sb, sa};
    for (const auto& b : blocks.blocks) c.marks.push_back(b.t_start);
    plot::render_chart(c, g.path("encounters.png"));
    return log::cat(
        "Residual (", unit, ") against where the nearest neighbour is, before and after the fit:\n\n",
        "![residual vs relative position](residual_vs_position.png)\n\n",
        "Recorded vs simulated through the flight, each encounter in its block:\n\n![encounters](encounters.png)\n\n");
}

// The stand's clock against the mocap's as the lab's time service measured it while recording
// (meta.json extra, dw-recorder export), if it did; whether the stamps are still as recorded; and
// the stand's own pipeline delay where the stand measured one. The explainer's clock effect
// (physics::clock_effect()) is the time between a force and the pose behind it beyond what the
// resimulation models (the chips' sample-and-hold): the clock's offset plus that delay.
struct MeasuredClock {
    double offset_s = 0;
    bool raw_stamps = true;
    std::optional<double> pipeline_delay_s;
    // What the fitted clock effect should estimate: the offset left in these stamps plus the delay.
    double expected_s() const { return (raw_stamps ? offset_s : 0.0) + pipeline_delay_s.value_or(0.0); }
};
std::optional<MeasuredClock> measured_clock(const flight::Flight& f) {
    if (!f.meta.clock_offset_measured_s) return std::nullopt;
    const json extra = json::parse(f.meta.extra_json, nullptr, false);
    const auto raw = extra.is_object() ? extra.find("raw_stamps") : extra.end();
    return MeasuredClock{*f.meta.clock_offset_measured_s, raw == extra.end() || !raw->is_boolean() || raw->get<bool>(),
                         f.meta.stand_pipeline_delay_s};
}

// What the report says of an effect: its accepted (final, refitted) result, else its latest score.
const CandidateResult* final_result(const ExplainResult& r, const std::string& effect) {
    const CandidateResult* found = nullptr;
    for (const auto& c : r.candidates)
        if (c.effect.name == effect) found = &c;
    for (const auto& c : r.accepted)
        if (c.effect.name == effect) found = &c;
    return found;
}

// "Measured live: ... Fitted: ..." — the time service and the stand's delay beside the explainer.
std::string measured_clock_text(const std::optional<MeasuredClock>& measured, const ExplainResult& r) {
    if (!measured) return "";
    const MeasuredClock& m = *measured;
    std::string fitted = "not fitted (not a candidate)";
    if (const auto* c = final_result(r, physics::clock_effect().name())) {
        const double e = m.expected_s();
        const bool holds = c->lo[0] <= e && e <= c->hi[0];
        fitted = log::cat(fixed(c->values[0], 4), " s [", fixed(c->lo[0], 4), ", ", fixed(c->hi[0], 4), "], ",
                          c->accepted ? "accepted" : "not accepted",
                          c->lo[0] == c->hi[0] ? ""
                          : holds              ? log::cat("; its interval holds the ", fixed(e, 4), " s measured")
                                  : log::cat("; ", fixed(std::min(std::abs(e - c->lo[0]), std::abs(e - c->hi[0])), 4),
                                             " s outside its interval: a delay neither measurement sees"));
    }
    const std::string delay =
        m.pipeline_delay_s ? log::cat("; the stand measured its own pipeline delay, ", fixed(*m.pipeline_delay_s, 4),
                                      " s (a simulated stand: the simulated air acts on the poses it is given, "
                                      "which arrive late)")
                           : "; the stand measured no pipeline delay of its own (a real stand's air has none)";
    return log::cat(
        "**Clock offset, measured beside fitted.** The explainer's ", physics::clock_effect().name(),
        " is the time between a force and the pose behind it beyond what the resimulation models (the chips' "
        "sample-and-hold): the stand's clock against "
        "the mocap's plus the stand's own pipeline delay. The lab's time service measured the clock while recording: ",
        fixed(m.offset_s, 4), " s",
        m.raw_stamps ? " (these stamps are as recorded)" : " (already taken out of these stamps by the export)", delay,
        ". Together ", fixed(m.expected_s(), 4), " s. The explainer's ", physics::clock_effect().name(), ": ", fitted,
        ".\n\n");
}

// One candidate's entry in report.json.
json candidate_json(const CandidateResult& c, const std::optional<MeasuredClock>& measured) {
    json j{{"effect", c.effect.name},
           {"params", params_json(c, false)},
           {"ci95", params_json(c, true)},
           {"heldout_rmse_before", axes_json(c.heldout_before)},
           {"heldout_rmse_after", axes_json(c.heldout_after)},
           {"delta_bic", c.delta_bic},
           {"accepted", c.accepted},
           {"heldout_z", c.t},
           {"note", c.note}};
    if (!c.indistinguishable.empty()) j["indistinguishable_from"] = c.indistinguishable;
    if (c.stand_in) j["stands_in"] = true;
    if (c.stand_in_z) j["stand_in_z"] = *c.stand_in_z;
    if (const auto& m = c.one_value)
        j["one_value"] = {{"axis", split_info(m->axis).name},
                          {"param", m->param},
                          {"low", m->low},
                          {"high", m->high},
                          {"z", m->z},
                          {"threshold", m->threshold},
                          {"tests", m->tested},
                          {"moved", m->moved}};
    if (const auto& s = c.short_of)
        j["short_of_discrepancy"] = {{"axis", kAxes[static_cast<std::size_t>(s->axis)]},
                                     {"effect_gain", s->effect_gain},
                                     {"discrepancy_gain", s->discrepancy_gain},
                                     {"together_gain", s->together_gain},
                                     {"adds_z", s->z}};  // together: the model and the discrepancy on top
    if (c.too_few_pieces)
        j["not_identifiable"] = {{"evidence_pieces", c.evidence_pieces},
                                 {"why", "its held-out evidence sits in too few pieces"}};
    if (measured && c.effect.type == &physics::clock_effect())
        j["measured"] = {{"offset_s", measured->offset_s}, {"expected_s", measured->expected_s()}};
    return j;
}

json discrepancy_json(const Discrepancy& g) {
    json j{{"model", kDiscrepancyModel},
           {"learnt", g.fitted},
           {"inputs", g.inputs},
           {"heldout_rmse_before", axes_json(g.heldout_before)},
           {"heldout_rmse_after", axes_json(g.heldout_after)},
           {"axis", kAxes[static_cast<std::size_t>(g.best_axis)]},
           {"heldout_z", g.fitted ? g.t : 0.0},
           {"gain", g.gain},
           {"significant", g.significant},
           {"note", g.note}};
    if (g.significant && !g.depends_on.empty()) {
        json shares = json::object();
        for (const auto& [name, share] : g.shares) shares[name] = share;
        j["depends_on"] = g.depends_on;
        j["shares"] = shares;
        j["sentence"] = g.sentence;
        json z = json::object();
        for (const auto& [name, value] : g.group_z) z[name] = value;
        j["structure"] = {{"group_z", z}, {"structured", g.structured}};
        if (g.structured) j["structure"]["by"] = g.structured_by;
    }
    return j;
}

json line_json(const SpectralLine& l) {
    return json{{"axis", kAxes[static_cast<std::size_t>(l.axis)]},
                {"hz", l.hz},
                {"power_over_local", l.ratio},
                {"false_alarm", l.false_alarm},
                {"searched", l.lines},
                {"significant", l.significant}};
}

json turbulence_json(const std::vector<BandTurbulence>& t) {
    json j = json::array();
    for (const auto& b : t)
        j.push_back({{"band", kBands[b.band].name}, {"samples", b.samples}, {"intensity", b.intensity}});
    return j;
}

// report.json: the machine-readable contract (FLIGHT_FORMAT.md, explain report).
json report_json(const ExplainResult& r, const ExplainOptions& o, const std::optional<MeasuredClock>& measured) {
    json j;
    j["format"] = "downwash-explain/1";
    json regions = json::array();
    for (const auto& g : r.regions)
        regions.push_back({{"axis", g.axis}, {"where", g.where}, {"mean_residual", g.mean_residual}, {"z", g.z}});
    j["mismatch"] = {
        {"detected", r.detected},
        {"noise_floor", axes_json(r.noise_floor)},
        {"regions", regions},
        {"excess",
         {{"before", axes_json(r.excess_before)},
          {"after", axes_json(r.excess_after)},
          {"threshold", o.detect_excess}}},
        {"spectrum", {{"before", line_json(r.line_before)}, {"after", line_json(r.line_after)}, {"alpha", kLineAlpha}}},
        {"variance_shares",
         {{"axis", flight::kAxes[static_cast<std::size_t>(r.shares.axis)]},
          {"total", r.shares.total},
          {"noise", r.shares.noise},
          {"turbulence", r.shares.turbulence},
          {"effects", r.shares.effects},
          {"discrepancy", r.shares.discrepancy},
          {"unexplained", r.shares.unexplained},
          {"explained_to_the_noise", r.shares.to_the_noise},
          {"modelled_to_the_noise", r.shares.modelled_to_the_noise}}},
        {"turbulence_by_band", turbulence_json(r.turbulence)}};
    json cands = json::array();
    for (const auto& e : o.candidates)  // each effect once: its accepted (final) or latest score
        if (const CandidateResult* c = final_result(r, e.name)) cands.push_back(candidate_json(*c, measured));
    j["candidates"] = cands;
    if (measured) {
        j["clock_offset_measured"] = {{"offset_s", measured->offset_s},
                                      {"by", "the lab's time service (processes/status clock_offset_s, median)"},
                                      {"expected_s", measured->expected_s()}};
        if (measured->pipeline_delay_s) j["clock_offset_measured"]["pipeline_delay_s"] = *measured->pipeline_delay_s;
    }
    json by = json::array();
    for (const auto& c : r.accepted) by.push_back(c.effect.name);
    j["explained_by"] = by;
    json families = json::array();
    for (const auto& v : r.families)
        families.push_back({{"family", v.family->name},
                            {"shared", v.family->shared},
                            {"members", v.members},
                            {"value", v.shared_value},
                            {"sentence", v.sentence}});
    j["families"] = families;
    j["unexplained"] = r.unexplained;
    j["fit"] = {{"heldout_rmse_before", axes_json(r.heldout_before)},
                {"heldout_rmse_after", axes_json(r.heldout_after)}};
    j["discrepancy"] = discrepancy_json(r.discrepancy);
    j["discrepancy"]["in_physics_file"] = !r.fitted.discrepancy.empty();
    j["physics_out"] = "physics.yaml";
    if (!o.physics.calibration.empty()) j["physics_calibration"] = o.physics.calibration;
    j["cross_validation"] = {
        {"blocks", flight::to_string(r.blocks)}, {"count", r.legs}, {"folds", o.folds}, {"samples", r.samples}};
    return j;
}

// The effects this flight cannot decide (CandidateResult::too_few_pieces in what the report says of them).
void md_not_identifiable(std::ostream& md, const ExplainResult& r, const ExplainOptions& o) {
    for (const auto& e : o.candidates) {
        const CandidateResult* c = final_result(r, e.name);
        if (!c || !c->too_few_pieces) continue;
        md << "**Not identifiable from this flight: " << e.name << "** — it passes the whole-flight test and removes "
           << fixed(c->gain * 100, 1) << " % of the held-out " << kAxes[static_cast<std::size_t>(c->best_axis)]
           << " error, but that evidence sits in " << fixed(c->evidence_pieces, 1)
           << " effective pieces, too few for the held-out test to reach its threshold; a flight with more passes "
              "would decide it.\n\n";
    }
}

// The report's opening: the flight, and what explains it.
void md_summary(std::ostream& md, const flight::Flight& f, const ExplainResult& r, const physics::EffectVoice& who,
                const std::string& calibration) {
    md << "# Mismatch report\n\n";
    md << "Flight: " << f.meta.formation << ", " << f.meta.neighbours.size() << " neighbour(s), "
       << (who.flying ? log::cat("a flying sufferer (wrench: ", flight::to_string(f.meta.wrench_source), ")")
                      : std::string("on a load stand"))
       << ", " << r.legs << " cross-validation blocks by " << flight::to_string(r.blocks) << ", " << r.samples
       << " wrench samples in them. Simulated with the given physics along the recorded poses, each vehicle with its "
          "own parameters "
          "(meta.json); residual = recorded − simulated"
       << (f.meta.moments_measured ? "" : "; the moments are not measured and take no part") << ". Analysis took "
       << fixed(r.seconds, 1) << " s.\n\n";
    if (f.meta.pose_source == flight::PoseSource::estimate)
        md << "The poses are the vehicles' own state estimates (meta.json pose_source: estimate), not motion capture: "
              "a force that moved a vehicle may already be partly in its estimated pose, and an estimator's error "
              "reads as a position offset or lag.\n\n";
    if (!calibration.empty())
        md << "The physics is calibrated (" << calibration
           << "): what is left is what that calibration did not cover.\n\n";
    if (!r.detected) {
        md << "**No mismatch**: the recording matches the simulation within its noise. No effect is claimed.\n\n";
    } else if (r.accepted.empty()) {
        md << "**A significant mismatch that no candidate explains** (`unexplained`). Where it is is below; no effect "
              "is claimed.\n\n";
    } else {
        md << "**Explained by: ";
        for (std::size_t k = 0; k < r.accepted.size(); ++k) md << (k ? ", " : "") << r.accepted[k].effect.name;
        md << "**"
           << (r.unexplained ? " — and a significant residual remains unexplained (see the maps after the fit)." : ".")
           << "\n\n";
        for (const auto& v : r.families) md << "**A family this flight cannot separate: " << v.sentence << ".**\n\n";
        for (const auto& c : r.accepted) md << paragraph(c, who) << alternatives(c) << "\n\n";
    }
}

// Where: the noise floor, the significant regions and the time-shift signatures.
void md_where(std::ostream& md, const ExplainResult& r, const ExplainOptions& o, const physics::EffectVoice& who) {
    md << "## Where: noise floor and significant regions\n\n"
       << shares_line(r.shares)
       << turbulence_line(r, physics::counted_intensity(physics::prediction_noise_of(o.physics))) << "Noise floor ("
       << describe(r.noise_floor_basis);
    if (r.noise_floor_basis == FloorBasis::far_samples)
        md << " " << physics::kNearSizes << " of its own motor distances horizontally";
    md << "): ";
    for (std::size_t a = 0; a < 6; ++a) md << kAxes[a] << " " << fixed(r.noise_floor[a], 4) << (a < 5 ? ", " : ".\n\n");
    if (r.regions.empty()) md << "No region departs from the simulation by more than |z| = " << o.region_z << ".\n\n";
    else {
        md << "| axis | where | mean residual | z |\n|---|---|---|---|\n";
        for (const auto& g : r.regions)
            md << "| " << g.axis << " | " << g.where << " | " << fixed(g.mean_residual, 3) << " | " << fixed(g.z, 1)
               << " |\n";
        md << "\nz: the bin's mean residual over its standard error, with the sample count reduced for "
              "autocorrelation.\n\n";
    }
    md << "### Signatures: the time shift that best aligns recording and simulation\n\n"
          "A clock offset or sensor lag gives the same shift everywhere; a wake transport delay grows with separation; "
          "a position "
       << (who.flying ? "offset gives shifts of opposite sign for passes in opposite directions."
                      : "offset gives shifts of opposite sign on +E and −E legs.")
       << "\n\n| legs (all: a flight without legs) | separation band | mean separation [m] | samples | best shift [s] "
          "|\n|---|---|---|---|---|\n";
    for (const auto& s : r.shifts)
        md << "| "
           << (s.direction > 0   ? "+E"
               : s.direction < 0 ? "−E"
                                 : "all")
           << " | " << s.band << " | " << fixed(s.separation_m, 2) << " | " << s.samples << " | " << fixed(s.shift_s, 3)
           << " |\n";
}

// The candidates with the rule they were judged by, and the held-out error per axis.
void md_candidates(std::ostream& md, const ExplainResult& r, const ExplainOptions& o) {
    md << "\n## Candidates\n\nEach fitted with Ceres (Huber loss) on the whole flight, then — if ΔBIC < −10 — in "
       << o.folds << "-fold blocked cross-validation by " << flight::to_string(r.blocks) << " (folds: block % "
       << o.folds
       << "). Accepted when the held-out error falls on some axis — z over 0.25 s pieces of the held-out blocks, the "
          "larger of the "
          "Wilcoxon signed-rank z and the self-normalised sum Σd/√Σd² (pieces where the candidate changes the "
          "prediction by under 0.1 σ left out) ≥ "
       << o.min_t << ", by ≥ " << o.min_gain * 100
       << " %, and the total held-out error falls — and when its value fitted on the nearest and the farthest third of "
          "separations agrees "
          "(else it stands in for a mismatch that depends on separation). A candidate that passes all but the z while "
          "its held-out evidence sits in so few pieces that the sum cannot reach the threshold is not identifiable "
          "from this flight (said in its verdict). Intervals: the wider of the fold jackknife "
          "and the "
          "covariance (inflated for autocorrelation); a leak between two axes' also includes the apparent leak the "
          "base model "
          "shows on the axes of the same kind where none is claimed.\n\n| round | effect | parameters [95 %] | ΔBIC | "
          "verdict |\n|---|---|---|---|---|\n";
    for (const auto& c : r.candidates)
        md << "| " << c.round << " | " << c.effect.name << " | " << params_text(c) << " | " << fixed(c.delta_bic, 1)
           << " | " << c.note << " |\n";
    md << "\n## Held-out error per axis\n\n| axis | before | after the effects | and a learnt discrepancy "
          "|\n|---|---|---|---|\n";
    for (std::size_t a = 0; a < 6; ++a)
        md << "| " << kAxes[a] << " | " << fixed(r.heldout_before[a], 4) << " | " << fixed(r.heldout_after[a], 4)
           << " | " << fixed(r.discrepancy.heldout_after[a], 4) << " |\n";
    md << "\n**What is left, learnt** (`discrepancy` in report.json; it names no physics, and it is the yardstick "
          "every accepted effect met: docs/EXPLAINER.md): "
       << kDiscrepancyModel << ", fitted on each fold's training blocks. " << r.discrepancy.note
       << ". Its held-out error before it is the fitted model's residual on the same samples ("
       << kAxes[static_cast<std::size_t>(r.discrepancy.best_axis)] << " "
       << fixed(r.discrepancy.heldout_before[static_cast<std::size_t>(r.discrepancy.best_axis)], 4) << ").\n";
    if (!r.discrepancy.sentence.empty())
        md << "\nWhat it depends on most (the held-out gain lost without each group of its inputs): it "
           << r.discrepancy.sentence << ".\n";
}

}  // namespace

namespace {
// The first non-finite number in `j` (its JSON path), if any: the JSON library would write it as
// null, where the report's contract has a number.
std::optional<std::string> non_finite(const json& j, const std::string& path) {
    if (j.is_number_float() && !std::isfinite(j.get<double>())) return path;
    for (auto it = j.begin(); (j.is_object() || j.is_array()) && it != j.end(); ++it) {
        const std::string inner =
            j.is_object() ? path + "." + it.key() : path + "[" + std::to_string(it - j.begin()) + "]";
        if (auto p = non_finite(*it, inner)) return p;
    }
    return std::nullopt;
}
}  // namespace

void write_report(const flight::Flight& f, const ExplainResult& r, const ExplainOptions& o, const std::string& out) {
    StagedFolder staged(out);  // the report and its figures appear together, or not at all
    const std::string& dir = staged.path();
    const auto measured = measured_clock(f);
    const json report = report_json(r, o, measured);
    if (const auto where = non_finite(report, "report"))
        throw RuntimeError(
            log::cat("report.json: ", *where, " is not a finite number: the analysis broke down; no report"));
    write_file((fs::path(dir) / "report.json").string(), report.dump(2) + "\n");
    write_file((fs::path(dir) / "physics.yaml").string(), physics::to_yaml(r.fitted));

    const Resimulation sim(f, o.physics);
    const auto blocks = flight::find_blocks(f, o.folds, physics::encounter_radii(f.meta, o.physics));
    const Figures figs{
        sim,
        describe(sim, blocks),
        sim.recorded(o.physics),
        sim.recorded(r.fitted),
        r.regions.empty() ? std::size_t{2} : static_cast<std::size_t>(physics::axis_index(r.regions.front().axis)),
        dir};
    const physics::EffectVoice who = voice_of(sim);
    const std::string figures_md = who.flying ? flying_figures(figs, blocks) : stand_figures(figs, r);

    std::ostringstream md;
    md_summary(md, f, r, who, o.physics.calibration);
    md_not_identifiable(md, r, o);
    md << measured_clock_text(measured, r);
    md_where(md, r, o, who);
    md_candidates(md, r, o);
    md << "\n## Figures\n\n"
       << figures_md
       << "The fitted physics: [physics.yaml](physics.yaml) (the simulator's configuration with the accepted effects "
          "on"
       << (r.fitted.discrepancy.empty()
               ? ").\n"
               : ", and the learnt discrepancy: `dw-sim replay --flight <this flight> --physics physics.yaml --out "
                 "<folder>` shows how much closer it brings the simulation to the recording).\n");
    write_file((fs::path(dir) / "report.md").string(), md.str());
    staged.commit();
}

}  // namespace dw::analysis
