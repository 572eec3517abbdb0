#include "analysis/proof.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "analysis/explain.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/subprocess.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

struct Truth {
    std::string effect, param;
    double value;
    std::size_t index = 0;  // into the effect's parameters
};

struct Case {
    std::string name, formation, hidden;
    std::function<void(physics::PhysicsConfig&)> hide;
    std::vector<Truth> truth;
    std::uint64_t seed = 1;
};

std::string fmt(double v, int p = 3) {
    std::ostringstream s;
    s << std::fixed << std::setprecision(p) << v;
    return s.str();
}

std::vector<Case> cases() {
    return {
        {"clock_offset", "single", "clock offset 0.1 s (legs both ways; the maps look right)",
         [](physics::PhysicsConfig& c) { c.effects.clock_offset = {true, 0.1}; }, {{"clock_offset", "offset_s", 0.1}}, 11},
        {"wake_transport", "leader_follower", "wake transport delay (jet law, scale 1)",
         [](physics::PhysicsConfig& c) { c.effects.wake_transport = {true, 1.0}; }, {{"wake_transport", "delay_scale", 1.0}}, 12},
        {"sensor_lag", "single", "stand lag, tau 0.08 s",
         [](physics::PhysicsConfig& c) { c.effects.sensor_lag = {true, 0.08}; }, {{"sensor_lag", "tau_s", 0.08}}, 13},
        {"jet_merging", "leader_follower3", "jet merging (only where jets overlap: K = 3, >= 1 m)",
         [](physics::PhysicsConfig& c) { c.effects.jet_merging.enabled = true; }, {{"jet_merging", "contraction", 0.8}}, 14},
        {"cell_crosstalk", "single", "crosstalk f_d -> f_e, 4 %",
         [](physics::PhysicsConfig& c) { c.effects.cell_crosstalk = {true, 2, 1, 0.04}; }, {{"cell_crosstalk", "coefficient", 0.04}}, 15},
        {"two_effects", "side_by_side", "clock offset 0.08 s and force scale 1.15",
         [](physics::PhysicsConfig& c) {
             c.effects.clock_offset = {true, 0.08};
             c.effects.force_scale = {true, 1.15};
         },
         {{"clock_offset", "offset_s", 0.08}, {"force_scale", "scale", 1.15}}, 16},
    };
}

void fly(const physics::PhysicsConfig& hidden, const std::string& formation, std::uint64_t seed, const std::string& dir) {
    fs::create_directories(fs::path(dir).parent_path());
    const std::string yaml = dir + ".physics.yaml";
    write_file(yaml, physics::to_yaml(hidden));
    run_sibling({"dw-sim", "fly", "--formation", formation, "--physics", yaml, "--seed", std::to_string(seed), "--out", dir, "--quiet"},
                dir + ".log");
}

}  // namespace

namespace {
bool wanted_null(const ProofOptions& o) { return o.cases.empty() || std::find(o.cases.begin(), o.cases.end(), "null") != o.cases.end(); }
}  // namespace

ProofResult run_proof(const ProofOptions& o) {
    auto say = [&](const std::string& s) {
        if (o.progress) o.progress(s);
    };
    std::vector<std::string> known{"null"};
    for (const auto& c : cases()) known.push_back(c.name);
    for (const auto& n : o.cases) {
        if (std::find(known.begin(), known.end(), n) == known.end()) {
            std::string list;
            for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
            throw InputError(log::cat("--cases: unknown case '", n, "' (expected ", list, ")"));
        }
    }
    if (wanted_null(o) && o.null_seeds < 1) throw InputError("--null-seeds: the null case needs at least 1 flight (or leave it out with --cases)");
    fs::create_directories(o.out_dir);
    ProofResult R;
    const physics::PhysicsConfig plain;  // what the explainer is given: every effect off
    auto wanted = [&](const std::string& n) { return o.cases.empty() || std::find(o.cases.begin(), o.cases.end(), n) != o.cases.end(); };
    for (const auto& c : cases()) {
        if (!wanted(c.name)) continue;
        const std::string dir = (fs::path(o.out_dir) / c.name).string();
        physics::PhysicsConfig hidden;
        c.hide(hidden);
        say(log::cat("case ", c.name, ": dw-sim fly --formation ", c.formation, " with ", c.hidden));
        fly(hidden, c.formation, c.seed, dir + "/flight");
        ExplainOptions eo;
        eo.physics = plain;
        eo.stop = o.stop;
        const auto f = flight::read_flight(dir + "/flight");
        const auto r = explain(f, eo);
        write_report(f, r, eo, dir + "/explain");
        ProofRow row{c.name, c.formation, c.hidden, "", "", "", "", true, "", r.seconds};
        for (const auto& a : r.accepted) row.found += (row.found.empty() ? "" : ", ") + a.effect.name;
        if (row.found.empty()) row.found = "(none)";
        for (const auto& t : c.truth) {
            const auto it = std::find_if(r.accepted.begin(), r.accepted.end(), [&](const CandidateResult& a) { return a.effect.name == t.effect; });
            row.truth += (row.truth.empty() ? "" : "; ") + t.param + " " + fmt(t.value, 3);
            if (it == r.accepted.end()) {
                row.pass = false;
                row.why += t.effect + " not found. ";
                continue;
            }
            const double v = it->values[t.index], lo = it->lo[t.index], hi = it->hi[t.index];
            row.fitted += (row.fitted.empty() ? "" : "; ") + fmt(v, 3) + " [" + fmt(lo, 3) + ", " + fmt(hi, 3) + "]";
            if (t.value < lo || t.value > hi) {
                row.pass = false;
                row.why += t.param + " outside the interval. ";
            }
            const auto ax = static_cast<std::size_t>(it->best_axis);
            row.rmse += (row.rmse.empty() ? "" : "; ") + std::string(flight::kAxes[ax]) + " " + fmt(r.heldout_before[ax], 3) + " → " + fmt(r.heldout_after[ax], 3);
            if (!(r.heldout_after[ax] < r.heldout_before[ax])) {
                row.pass = false;
                row.why += "held-out error not reduced. ";
            }
        }
        for (const auto& a : r.accepted)
            if (std::none_of(c.truth.begin(), c.truth.end(), [&](const Truth& t) { return t.effect == a.effect.name; })) {
                row.pass = false;
                row.why += a.effect.name + " claimed but not hidden. ";
            }
        say(log::cat("  found ", row.found, " (", r.seconds, " s): ", row.pass ? "PASS" : "FAIL " + row.why));
        R.rows.push_back(row);
    }
    if (wanted("null")) {
        for (int k = 0; k < o.null_seeds; ++k) {
            const std::string dir = (fs::path(o.out_dir) / log::cat("null_", k)).string();
            fly(plain, "single", 100 + static_cast<std::uint64_t>(k), dir + "/flight");
            ExplainOptions eo;
            eo.physics = plain;
            eo.stop = o.stop;
            const auto f = flight::read_flight(dir + "/flight");
            const auto r = explain(f, eo);
            write_report(f, r, eo, dir + "/explain");
            ++R.null_total;
            std::string found;
            for (const auto& a : r.accepted) found += (found.empty() ? "" : ", ") + a.effect.name;
            if (r.accepted.empty()) ++R.null_clean;
            say(log::cat("null seed ", 100 + k, ": ", found.empty() ? "nothing claimed" : "claimed " + found, " (", r.seconds, " s)"));
        }
        ProofRow row{"null", "single", "nothing (noise and turbulence only)", log::cat(R.null_clean, " of ", R.null_total, " seeds claim nothing"),
                     "–", "–", "–", R.null_clean * 10 >= R.null_total * 9, "", 0};
        if (!row.pass) row.why = "effects claimed on noise";
        R.rows.push_back(row);
    }
    // A proof of nothing proves nothing: no rows, or a null case without flights, fails.
    R.pass = !R.rows.empty() && (!wanted("null") || R.null_total > 0) &&
             std::all_of(R.rows.begin(), R.rows.end(), [](const ProofRow& r) { return r.pass; });
    std::ostringstream md;
    md << "| case | flight | hidden effect | effect found | true parameter | fitted [95 %] | held-out RMSE before → after | verdict |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : R.rows)
        md << "| " << r.name << " | " << r.formation << " | " << r.hidden << " | " << r.found << " | " << r.truth << " | " << r.fitted << " | "
           << r.rmse << " | " << (r.pass ? "pass" : "FAIL: " + r.why) << " |\n";
    R.table_path = (fs::path(o.out_dir) / "proof.md").string();
    write_file(R.table_path, md.str());
    return R;
}

}  // namespace dw::analysis
