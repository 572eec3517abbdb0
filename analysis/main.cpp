// dw-explain: when a recording and the simulation of the same flight differ, locate where, name
// the missing physics, model it and show the fit improve. `dw-explain proof` shows it works.
#include <cstdio>
#include <iostream>
#include <sstream>

#include "analysis/coverage.hpp"
#include "analysis/explain.hpp"
#include "analysis/proof.hpp"
#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "recordings/recordings.hpp"

namespace {

// "a,b,,c" -> {a, b, c}
std::vector<std::string> split_list(const std::string& text) {
    std::vector<std::string> out;
    std::stringstream in(text);
    for (std::string item; std::getline(in, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

int run(int argc, char** argv) {
    CLI::App app{"dw-explain: locate where a recording departs from the simulation, name the missing physics, fit it, re-simulate"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    std::string physics_path, real, out, effects;
    std::uint64_t seed = 1;
    bool quiet = false;
    app.add_option("--physics", physics_path, "the physics configuration to compare with (default: config/physics.example.yaml's defaults)");
    app.add_option("--real", real, "the recording: a flight folder (downwash-flight/1) or an .mcap file");
    app.add_option("--out", out, "output folder: report.json, report.md, physics.yaml, figures");
    app.add_option("--effects", effects, "candidates, comma-separated (default: every effect of the vocabulary)");
    app.add_option("--seed", seed, "seed (the analysis is deterministic; recorded in the report)")->check(dw::cli::in(dw::kSeedRange));
    app.add_flag("--quiet", quiet, "no progress");
    auto* proof = app.add_subcommand("proof", "fly flights with hidden effects (dw-sim fly), explain them, check what was found");
    dw::analysis::ProofOptions po;
    std::string cases;
    proof->add_option("--out", po.out_dir, "output folder (flights, reports, proof.md)")->required();
    proof->add_option("--null-seeds", po.null_seeds, "null flights (noise only)")->check(dw::cli::in({0, 100}));
    proof->add_option("--cases", cases, "clock_offset, wake_transport, sensor_lag, jet_merging, cell_crosstalk, two_effects, null (default: all)");
    auto* real_proof = app.add_subcommand("real-proof", "conceal known effects in recorded flights and check each is found on top of the flight's own fit");
    dw::analysis::RealProofOptions rpo;
    std::string real_cases, real_physics;
    real_proof->add_option("--flights", rpo.flights, "flight folders (e.g. dw-import's)")->required();
    real_proof->add_option("--physics", real_physics, "the physics to explain them with (e.g. config/physics.crazyflie.yaml)");
    real_proof->add_option("--out", rpo.out_dir, "output folder (reports, proof.md)")->required();
    real_proof->add_option("--cases", real_cases, "clock_offset, force_scale, sensor_lag, cell_crosstalk (default: all)");
    auto* coverage = app.add_subcommand("coverage", "measure how often the 95 % intervals hold the hidden value, over many simulated flights per effect");
    dw::analysis::CoverageOptions co;
    std::string coverage_effects;
    coverage->add_option("--out", co.out_dir, "output folder (coverage.md)")->required();
    coverage->add_option("--seeds", co.seeds, "flights per effect")->check(dw::cli::in({1, 1000}));
    coverage->add_option("--legs", co.legs, "legs per flight")->check(dw::cli::in({5, 1000}));
    coverage->add_option("--jobs", co.jobs, "flights at once")->check(dw::cli::in({1, 64}));
    coverage->add_option("--effects", coverage_effects, "effects, comma-separated (default: every one a flight over the stand can show)");
    dw::cli::parse(app, argc, argv);
    dw::log::set_level(dw::log::parse_level(base.log_level));
    auto progress = [quiet](const std::string& s) {
        if (!quiet) std::cerr << "dw-explain: " << s << "\n";
    };
    if (proof->parsed()) dw::require_output_dir(po.out_dir, "--out");
    if (real_proof->parsed()) {
        dw::require_output_dir(rpo.out_dir, "--out");
        rpo.physics = physics_path.empty() && real_physics.empty() ? dw::physics::PhysicsConfig{}
                                                                     : dw::physics::load_physics(real_physics.empty() ? physics_path : real_physics);
        rpo.cases = split_list(real_cases);
        rpo.progress = progress;
        rpo.stop = dw::Shutdown::instance().token();
        const auto r = dw::analysis::run_real_proof(rpo);
        std::cout << dw::read_file(r.table_path, "proof table");
        std::cout << (r.pass ? "PROOF PASSED" : "PROOF FAILED") << " (" << r.table_path << ")\n";
        if (!r.pass) throw dw::RuntimeError("PROOF FAILED: see " + r.table_path);
        return 0;
    }
    if (coverage->parsed()) {
        dw::require_output_dir(co.out_dir, "--out");
        co.effects = split_list(coverage_effects);
        co.progress = progress;
        co.stop = dw::Shutdown::instance().token();
        const auto r = dw::analysis::run_coverage(co);
        std::cout << dw::read_file(r.table_path, "coverage table");
        if (!r.pass) throw dw::RuntimeError("COVERAGE BELOW TARGET: see " + r.table_path);
        return 0;
    }
    if (proof->parsed()) {
        po.cases = split_list(cases);
        po.progress = progress;
        po.stop = dw::Shutdown::instance().token();
        const auto r = dw::analysis::run_proof(po);
        std::cout << dw::read_file(r.table_path);
        std::cout << (r.pass ? "PROOF PASSED" : "PROOF FAILED") << " (" << r.table_path << ")\n";
        if (!r.pass) throw dw::RuntimeError("PROOF FAILED: see " + r.table_path);
        return 0;
    }
    if (real.empty()) throw dw::InputError("--real: required (a flight folder or an .mcap recording)");
    if (out.empty()) throw dw::InputError("--out: required (the report's folder)");
    dw::require_output_dir(out, "--out");
    dw::analysis::ExplainOptions o;
    o.physics = physics_path.empty() ? dw::physics::PhysicsConfig{} : dw::physics::load_physics(physics_path);
    if (!effects.empty()) {
        o.candidates = dw::analysis::effects_named(split_list(effects));
    }
    o.seed = seed;
    o.progress = progress;
    o.stop = dw::Shutdown::instance().token();
    // A recording is explained with its stamps as recorded: the explainer checks the clocks itself,
    // and the report puts the time service's measurement beside what it fits.
    dw::recordings::ExportOptions raw;
    raw.raw_stamps = true;
    raw.stop = dw::Shutdown::instance().token();
    const auto f = dw::recordings::read_flight_or_recording(real, raw);
    const auto r = dw::analysis::explain(f, o);
    dw::analysis::write_report(f, r, o, out);
    std::string by;
    for (const auto& c : r.accepted) by += (by.empty() ? "" : ", ") + c.effect.name;
    std::cout << (r.detected ? (by.empty() ? "mismatch found, not explained" : "explained by: " + by) : "no mismatch")
              << (r.unexplained && !by.empty() ? " (a residual remains unexplained)" : "") << "; report: " << out << "/report.md ("
              << r.seconds << " s)\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-explain", [&] { return run(argc, argv); });
}
