#include "analysis/unnamed.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>
#include <sstream>

#include "analysis/explain.hpp"
#include "analysis/study.hpp"
#include "analysis/replay.hpp"
#include "analysis/resimulation.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/numbers.hpp"
#include "core/parallel.hpp"
#include "physics/effect_types.hpp"
#include "physics/flight_sim.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

// How much of each mismatch is hidden: physical sizes a real stand meets, not tuned to a flight.
constexpr double kCreep_N = 0.2;             // a zero that creeps this far on f_d over the flight
constexpr double kGainCreep = 0.3;           // a gain that creeps from 1 to 1 + this over the flight
constexpr double kSaturationFraction = 0.5;  // a sensor that stops following at this fraction of the peak
constexpr double kDriftPerMetre = 0.1;       // wakes drift sideways 0.1 m per metre they fall (~6°)
constexpr double kWiderJet = 1.4;            // the jet's width coefficient this times the model's
constexpr double kDirectionGain = 0.15;      // the push ±15 % with the nearest neighbour's direction of travel
constexpr double kMovingMps = 0.1;           // ... when it moves faster than this along E
constexpr double kPeriodicFraction = 0.15;   // a disturbance of ±15 % of the force ...
constexpr double kPeriodicHz = 2.3;          // ... at this frequency (a beat between rotors)
constexpr double kFamilyClock_s = 0.08;      // the family case: a clock offset on a flight at one height
constexpr double kFamilyAltitude_m = 0.8;
constexpr std::uint64_t kUnseenSeed = 1000;  // the unseen flight of a case: its seed plus this

using Recording = std::function<void(flight::Flight&)>;

struct Case {
    std::string name, formation, along, hidden;
    std::function<void(physics::PhysicsConfig&)> air;  // what the air and the stand do (may be empty)
    Recording recording;                               // what happens to the recording after (may be empty)
    std::function<void(physics::GridOptions&)> grid;   // the flight's grid (may be empty)
    std::vector<std::string> truly;  // effects of the vocabulary that truly are in it (several: a family to name)
    std::uint64_t seed = 1;
};

// The effects of a family (each may be what a case's mismatch is named as).
std::vector<std::string> members_of(const physics::EffectFamily& family) {
    std::vector<std::string> out;
    for (const auto* t : physics::effect_types())
        if (t->family() == &family) out.push_back(t->name());
    return out;
}

// The flight's first and last wrench stamps.
std::pair<double, double> span_of(const flight::Flight& f) { return {f.wrench.front().t, f.wrench.back().t}; }

Recording creeping_zero() {
    return [](flight::Flight& f) {
        const auto [t0, t1] = span_of(f);
        for (auto& s : f.wrench) s.w[2] += kCreep_N * (s.t - t0) / (t1 - t0);
    };
}

Recording creeping_gain() {
    return [](flight::Flight& f) {
        const auto [t0, t1] = span_of(f);
        for (auto& s : f.wrench)
            for (auto& x : s.w) x *= 1 + kGainCreep * (s.t - t0) / (t1 - t0);
    };
}

Recording saturating_sensor() {
    return [](flight::Flight& f) {
        std::array<double, 6> peak{};
        for (const auto& s : f.wrench)
            for (std::size_t a = 0; a < 6; ++a) peak[a] = std::max(peak[a], std::abs(s.w[a]));
        for (auto& s : f.wrench)
            for (std::size_t a = 0; a < 6; ++a) {
                const double limit = kSaturationFraction * peak[a];
                if (limit > 0) s.w[a] = limit * std::tanh(s.w[a] / limit);
            }
    };
}

// The wake falls sideways (+N) kDriftPerMetre per metre below its vehicle: the force follows a
// vehicle displaced that far, so the recorded vehicle sits that far on the other side.
Recording drifting_wakes() {
    return [](flight::Flight& f) {
        const int sufferer = f.find_body(f.meta.sufferer);
        double d = 0, n = 0;
        for (const auto& p : f.poses)
            if (static_cast<int>(p.body) == sufferer) d += p.p[2], n += 1;
        d /= std::max(n, 1.0);
        for (auto& p : f.poses)
            if (static_cast<int>(p.body) != sufferer) p.p[0] -= kDriftPerMetre * std::max(0.0, d - p.p[2]);
    };
}

Recording direction_gain() {
    return [](flight::Flight& f) {
        const Resimulation r(f);
        for (auto& s : f.wrench) {
            const double ve = r.velocity(0, s.t)[1];
            if (std::abs(ve) < kMovingMps) continue;
            for (auto& x : s.w) x *= 1 + kDirectionGain * (ve > 0 ? 1 : -1);
        }
    };
}

Recording periodic_disturbance() {
    return [](flight::Flight& f) {
        for (auto& s : f.wrench)
            for (auto& x : s.w) x *= 1 + kPeriodicFraction * std::sin(2 * M_PI * kPeriodicHz * s.t);
    };
}

// What happens to the recording: the stand's zero, gain or response, the wakes' path, the push.
std::vector<Case> recording_cases() {
    return {
        {"creeping_zero",
         "single",
         "time",
         log::cat("f_d's zero creeps ", kCreep_N, " N over the flight"),
         {},
         creeping_zero(),
         {},
         {},
         31},
        {"creeping_gain",
         "single",
         "time",
         log::cat("the gain creeps from 1 to ", 1 + kGainCreep, " over the flight"),
         {},
         creeping_gain(),
         {},
         {},
         32},
        {"saturating_sensor",
         "single",
         "predicted push",
         log::cat("the stand stops following: limit × tanh(f / limit), limit ", kSaturationFraction,
                  " × each axis's peak"),
         {},
         saturating_sensor(),
         {},
         {},
         33},
        {"drifting_wakes",
         "single",
         "neighbour height",
         log::cat("wakes drift ", kDriftPerMetre, " m north per metre they fall"),
         {},
         drifting_wakes(),
         {},
         {},
         34},
        {"direction_gain",
         "single",
         "direction of travel",
         log::cat("the push ± ", kDirectionGain * 100, " % with the neighbour's direction of travel"),
         {},
         direction_gain(),
         {},
         {},
         36},
        {"periodic",
         "single",
         "spectrum",
         log::cat("± ", kPeriodicFraction * 100, " % of the force at ", kPeriodicHz, " Hz"),
         {},
         periodic_disturbance(),
         {},
         {},
         37},
    };
}

// What the air does: a wider jet, another aggregation, another jet; and a named effect the flight cannot separate.
std::vector<Case> air_cases() {
    using physics::PhysicsConfig;
    return {
        {"wider_jet",
         "single",
         "horizontal separation",
         log::cat("the jet's width coefficient × ", kWiderJet),
         [](PhysicsConfig& c) { c.bauersfeld.width *= kWiderJet; },
         {},
         {},
         {},
         35},
        {"velocity_superposition",
         "leader_follower",
         "aggregation",
         "jets' velocities add before the drag",
         [](PhysicsConfig& c) { c.aggregation = physics::Aggregation::velocity_superposition; },
         {},
         {},
         // The push family's meaning includes "the aggregate is not the sum of single jets": this is one
         // such aggregate. Where the jets always share the push, a gain of it is its family too.
         members_of(physics::kPushFamily),
         38},
        {"jain_jet",
         "single",
         "the jet",
         "the Jain jet instead of Bauersfeld's",
         [](PhysicsConfig& c) { c.jet_model = physics::JetModelKind::jain; },
         {},
         {},
         {},
         39},
        {"delay_family",
         "single",
         "family",
         log::cat("clock offset ", kFamilyClock_s, " s on a flight at one height (", kFamilyAltitude_m, " m)"),
         [](PhysicsConfig& c) { physics::clock_effect().set(c.effects, {kFamilyClock_s}); },
         {},
         [](physics::GridOptions& g) { g.altitudes_m = {kFamilyAltitude_m}; },
         members_of(physics::kDelayFamily),
         40},
    };
}

std::vector<Case> cases() {
    auto out = recording_cases();
    for (auto& c : air_cases()) out.push_back(std::move(c));
    return out;
}

std::vector<std::string> case_names() {
    std::vector<std::string> out{"null"};
    for (const auto& c : cases()) out.push_back(c.name);
    return out;
}

// One flight of the case (none: a null flight), flown with its air and its recording changed,
// written to dir/<name> with the air's physics beside it.
flight::Flight fly_case(const Case* c, std::uint64_t seed, const std::string& dir, const std::string& name,
                        const UnnamedOptions& o) {
    physics::PhysicsConfig air;
    if (c && c->air) c->air(air);
    physics::FlyOptions fly;
    fly.formation = c ? c->formation : "single";
    fly.seed = seed;
    fly.grid.legs = o.legs;
    fly.stop = o.stop;
    if (c && c->grid) c->grid(fly.grid);
    auto f = physics::simulate_flight(air, fly).flight;
    if (c && c->recording) c->recording(f);
    fs::create_directories(dir);
    write_file(dir + "/" + name + ".physics.yaml", physics::to_yaml(air));
    flight::write_flight(f, dir + "/" + name);
    return f;
}

// One flight: flown, explained with the plain physics, its report written.
ExplainResult fly_and_explain(const Case* c, std::uint64_t seed, const std::string& dir, const UnnamedOptions& o) {
    const auto f = fly_case(c, seed, dir, "flight", o);
    ExplainOptions eo;
    eo.stop = o.stop;
    auto r = explain(f, eo);
    write_report(f, r, eo, dir + "/explain");
    return r;
}

// The fitted physics, its learnt discrepancy and all, replayed (dw-sim replay) on a flight it has
// not seen: the same case flown again with another seed, every block of it held out. Its RMS error on
// the discrepancy's best axis, without and with the discrepancy.
struct Unseen {
    bool carried = false;
    std::size_t axis = 2;
    double without = 0, with = 0;
};

Unseen on_unseen_flight(const Case& c, const ExplainResult& r, const std::string& dir, const UnnamedOptions& o) {
    Unseen u;
    if (r.fitted.discrepancy.empty()) return u;
    const auto f = fly_case(&c, c.seed + kUnseenSeed, dir, "unseen_flight", o);
    const Replay rp = replay(f, r.fitted);
    const auto with = rp.with_discrepancy();
    u.carried = true;
    u.axis = static_cast<std::size_t>(r.discrepancy.best_axis);
    u.without = rms_on_blocks(f, rp, rp.physics)[u.axis];
    u.with = rms_on_blocks(f, rp, with)[u.axis];
    return u;
}

std::string names_of(const std::vector<CandidateResult>& v) {
    std::string out;
    for (const auto& c : v) out += (out.empty() ? "" : ", ") + c.effect.name;
    return out;
}

UnnamedRow row_of(const Case& c, const ExplainResult& r, const Unseen& u) {
    UnnamedRow row{c.name, c.formation, c.along, c.hidden, r.detected, r.unexplained, names_of(r.accepted)};
    for (const auto& v : r.families) row.accepted += log::cat(" (", v.sentence, ")");
    for (const auto& k : r.candidates) {
        std::string why;
        if (k.short_of) why = log::cat(" falls short of the discrepancy on ", flight::kAxes[k.short_of->axis]);
        else if (k.stand_in && k.one_value) why = log::cat(" moves along ", split_info(k.one_value->axis).name);
        const std::string item = k.effect.name + why;
        if (!why.empty() && row.stand_ins.find(item) == std::string::npos)
            row.stand_ins += (row.stand_ins.empty() ? "" : "; ") + item;
    }
    const auto& g = r.discrepancy;
    const auto a = static_cast<std::size_t>(g.best_axis);
    row.discrepancy =
        log::cat(flight::kAxes[a], " ", csv_cell(g.heldout_before[a], 3), " → ", csv_cell(g.heldout_after[a], 3), " (",
                 fixed(g.gain * 100, 0), " %, z ", fixed(g.t, 1), ")");
    row.unseen =
        u.carried ? log::cat(flight::kAxes[u.axis], " ", csv_cell(u.without, 3), " → ", csv_cell(u.with, 3)) : "–";
    row.pass = r.detected;
    if (!r.detected) row.why += "not detected. ";
    if (u.carried && !(u.with < u.without))
        row.pass = false, row.why += "the discrepancy does not carry to a flight it has not seen. ";
    for (const auto& k : r.accepted)
        if (std::find(c.truly.begin(), c.truly.end(), k.effect.name) == c.truly.end()) {
            row.pass = false;
            row.why += k.effect.name + " accepted. ";
        }
    if (!g.fitted) row.pass = false, row.why += "no discrepancy learnt. ";
    if (c.truly.size() > 1 && !r.accepted.empty() && r.families.empty())  // a family: never one member alone
        row.pass = false, row.why += "one member of the family named alone. ";
    return row;
}

std::string table(const std::vector<UnnamedRow>& rows, int clean, int total) {
    std::ostringstream md;
    md << "| case | flight | varies along | hidden | detected | accepted | refused as stand-ins | discrepancy: "
          "held-out "
          "RMSE before → after | the fitted physics replayed on an unseen flight: RMSE without → with the discrepancy "
          "| verdict |\n|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
        md << "| " << r.name << " | " << r.formation << " | " << r.along << " | " << r.hidden << " | "
           << (r.detected ? "yes" : "no") << " | " << (r.accepted.empty() ? "nothing" : r.accepted) << " | "
           << (r.stand_ins.empty() ? "–" : r.stand_ins) << " | " << r.discrepancy << " | " << r.unseen << " | "
           << (r.pass ? "pass" : "FAIL: " + r.why) << " |\n";
    if (total > 0)
        md << "| null | single | – | nothing (noise and turbulence only) | " << total - clean << " of " << total
           << " detected | – | – | – | – | " << (clean == total ? "pass" : "FAIL") << " |\n";
    return md.str();
}

}  // namespace

std::string unnamed_case_list() { return log::join(case_names()); }

UnnamedResult run_unnamed(const UnnamedOptions& o) {
    StudyProgress say(o.progress);
    const auto known = case_names();
    require_known_cases(o.cases, known);
    const bool nulls = o.cases.empty() || find_name(o.cases, "null");
    std::vector<Case> chosen;
    for (auto& c : cases())
        if (o.cases.empty() || find_name(o.cases, c.name)) chosen.push_back(std::move(c));
    const int null_count = nulls ? o.null_seeds : 0;
    StagedFolder staged(o.out_dir);
    const fs::path out = staged.path();
    std::vector<UnnamedRow> rows(chosen.size());
    std::vector<char> clean(static_cast<std::size_t>(null_count), 0);
    parallel_for(chosen.size() + clean.size(), o.jobs, [&](std::size_t i) {
        if (i >= chosen.size()) {
            const std::size_t k = i - chosen.size();
            const auto r = fly_and_explain(nullptr, 100 + k, (out / log::cat("null_", k)).string(), o);
            clean[k] = !r.detected;
            return say(
                log::cat("null seed ", 100 + k, ": ", r.detected ? "DETECTED" : "clean", " (", r.seconds, " s)"));
        }
        const Case& c = chosen[i];
        say(log::cat("case ", c.name, ": ", c.hidden));
        const auto r = fly_and_explain(&c, c.seed, (out / c.name).string(), o);
        rows[i] = row_of(c, r, on_unseen_flight(c, r, (out / c.name).string(), o));
        say(log::cat("case ", c.name, ": ", rows[i].pass ? "pass" : "FAIL " + rows[i].why, " (", r.seconds, " s)"));
    });
    UnnamedResult R;
    R.rows = rows;
    R.null_total = null_count;
    R.null_clean = static_cast<int>(std::count(clean.begin(), clean.end(), 1));
    R.pass = (!R.rows.empty() || R.null_total > 0) && R.null_clean == R.null_total &&
             std::all_of(R.rows.begin(), R.rows.end(), [](const UnnamedRow& r) { return r.pass; });
    write_file((out / kUnnamedTableFile).string(), table(R.rows, R.null_clean, R.null_total));
    staged.commit();
    R.table_path = (fs::path(o.out_dir) / kUnnamedTableFile).string();
    return R;
}

}  // namespace dw::analysis
