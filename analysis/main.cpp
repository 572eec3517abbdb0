// dw-explain: when a recording and the simulation of the same flight differ, locate where, name
// the missing physics, model it and show the fit improve. `dw-explain proof` shows it works.
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <sstream>

#include "analysis/calibrate.hpp"
#include "analysis/coverage.hpp"
#include "analysis/explain.hpp"
#include "analysis/proof.hpp"
#include "analysis/session.hpp"
#include "analysis/session_proof.hpp"
#include "analysis/unnamed.hpp"
#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "physics/effect_types.hpp"
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

using Progress = std::function<void(const std::string&)>;

// What every dw-explain command takes from the root's options: --physics and --quiet.
struct Root {
    std::string physics_path;
    bool quiet = false;
    Progress progress() const {
        return [quiet = quiet](const std::string& s) {
            if (!quiet) dw::log::progress(s);
        };
    }
};

// A dw-explain subcommand: given the root's options.
struct ExplainTool : dw::cli::Command {
    explicit ExplainTool(const Root& r) : root(r) {}
    const Root& root;
    CLI::App* sub = nullptr;
};

// What a study prints after its table: the line when it passes (none: the table alone), the word when it fails.
struct Verdict {
    const char* passed;
    const char* failed;
};
constexpr Verdict kProofVerdict{"PROOF PASSED", "PROOF FAILED"};
constexpr Verdict kCoverageVerdict{nullptr, "COVERAGE BELOW TARGET"};
constexpr const char* kJobsHelp = "flights flown and explained at once (each explanation is one thread)";

// Prints a study's table and its verdict; a failed verdict is a runtime failure.
int finish(const std::string& table_path, bool pass, const Verdict& v) {
    std::cout << dw::read_file(table_path, "table");
    if (v.passed) std::cout << (pass ? v.passed : v.failed) << " (" << table_path << ")\n";
    if (!pass) throw dw::RuntimeError(std::string(v.failed) + ": see " + table_path);
    return 0;
}

// What every study shares: its output folder checked first, progress, and the stop on SIGINT.
template <class Options>
void prepare(Options& o, const Progress& progress) {
    dw::require_output_dir(o.out_dir, "--out");
    o.progress = progress;
    o.stop = dw::Shutdown::instance().token();
}

// The options the simulated studies share: --out, --null-seeds, --jobs, --cases.
template <class Options>
void add_study_options(CLI::App* sub, Options& o, std::string& cases, const std::string& case_list,
                       const char* out_help) {
    sub->add_option("--out", o.out_dir, out_help)->required();
    sub->add_option("--null-seeds", o.null_seeds, "null flights (noise only)")->check(dw::cli::in({0, 100}));
    sub->add_option("--jobs", o.jobs, kJobsHelp)->check(dw::cli::in(dw::kJobsRange));
    sub->add_option("--cases", cases, case_list + " (default: all)");
}

// A simulated study run: its table printed, its verdict a pass or a runtime failure.
template <class Options, class Run>
int run_study(Options& o, const std::string& cases, const Progress& progress, Run run) {
    prepare(o, progress);
    o.cases = split_list(cases);
    const auto r = run(o);
    return finish(r.table_path, r.pass, kProofVerdict);
}

// `dw-explain proof`: simulated flights with hidden effects.
struct ProofCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::ProofOptions options;
    std::string cases;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("proof",
                                 "simulate flights with hidden effects (in-process, as dw-sim fly does), explain them, "
                                 "check what was found");
        add_study_options(sub, options, cases, dw::analysis::proof_case_list(),
                          "output folder (flights, reports, proof.md)");
        return sub;
    }
    int run() override { return run_study(options, cases, root.progress(), dw::analysis::run_proof); }
};

// `dw-explain unnamed`: simulated flights with mismatches the vocabulary has no word for.
struct UnnamedCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::UnnamedOptions options;
    std::string cases;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("unnamed",
                                 "simulate flights with mismatches no effect of the vocabulary names, explain them, "
                                 "check each is detected, nothing named for it and what is left modelled");
        add_study_options(sub, options, cases, dw::analysis::unnamed_case_list(),
                          "output folder (flights, reports, unnamed.md)");
        sub->add_option("--legs", options.legs, "legs per flight")
            ->check(dw::cli::in({5, 1000}))
            ->capture_default_str();
        return sub;
    }
    int run() override { return run_study(options, cases, root.progress(), dw::analysis::run_unnamed); }
};

// The sizes of the concealed effects, each an option its effect declares.
void add_concealed_options(CLI::App* sub, dw::analysis::Concealed& c) {
    for (const auto* t : dw::physics::effect_types())
        if (const auto k = t->real_concealment(); k && c.count(t->name()))
            sub->add_option(k->option, c[t->name()], t->name() + " case: " + k->option_help)
                ->check(dw::cli::in(k->range))
                ->capture_default_str();
}

// The options the studies on recorded flights share: --physics, --out, --cases and the concealed sizes.
template <class Options>
void add_recorded_study_options(CLI::App* sub, Options& o, std::string& physics, std::string& cases,
                                const char* out_help) {
    sub->add_option("--physics", physics, "the physics to explain them with (e.g. config/physics.crazyflie.yaml)");
    sub->add_option("--out", o.out_dir, out_help)->required();
    sub->add_option("--cases", cases, dw::analysis::concealment_names() + " (default: all)");
    add_concealed_options(sub, o.concealed);
}

// A study on recorded flights: its physics (its own --physics, else the main one), its cases, its verdict.
template <class Options, class Run>
int run_recorded_study(Options& o, const std::string& physics, const Root& root, const std::string& cases, Run run) {
    prepare(o, root.progress());
    const std::string path = physics.empty() ? root.physics_path : physics;
    o.physics = dw::physics::physics_or_defaults(path);
    o.cases = split_list(cases);
    const auto r = run(o);
    return finish(r.table_path, r.pass, kProofVerdict);
}

// `dw-explain real-proof`: effects concealed in recorded flights.
struct RealProofCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::RealProofOptions options;
    std::string cases, physics;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand(
            "real-proof",
            "conceal known effects in recorded flights and check each is found on top of the flight's own fit");
        sub->add_option("--flights", options.flights, "flight folders (e.g. dw-import's)")->required();
        add_recorded_study_options(sub, options, physics, cases, "output folder (reports, proof.md)");
        return sub;
    }
    int run() override { return run_recorded_study(options, physics, root, cases, dw::analysis::run_real_proof); }
};

// `dw-explain coverage`: how often the intervals hold the hidden value.
struct CoverageCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::CoverageOptions options;
    std::string effects;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand(
            "coverage",
            "measure how often the 95 % intervals hold the hidden value, over many simulated flights per effect");
        sub->add_option("--out", options.out_dir, "output folder (coverage.md)")->required();
        sub->add_option("--seeds", options.seeds, "flights per effect")->check(dw::cli::in({1, 1000}));
        sub->add_option("--legs", options.legs, "legs per flight")->check(dw::cli::in({5, 1000}));
        sub->add_option("--jobs", options.jobs, kJobsHelp)->check(dw::cli::in(dw::kJobsRange));
        sub->add_option("--effects", effects,
                        "effects, comma-separated (default: every one a flight over the stand can show)");
        return sub;
    }
    int run() override {
        prepare(options, root.progress());
        options.effects = split_list(effects);
        const auto r = dw::analysis::run_coverage(options);
        return finish(r.table_path, r.pass, kCoverageVerdict);
    }
};

// `dw-explain calibrate`: the physics fitted per vehicle class on many flights, checked on trials left out.
struct CalibrateCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::CalibrateOptions options;
    std::string physics;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("calibrate",
                                 "fit the physics per vehicle class on many flights; validate by leaving trials out");
        sub->add_option("--flights", options.flights, "flight folders (e.g. dw-import's), two trials or more")
            ->required();
        sub->add_option("--physics", physics, "the base physics (e.g. config/physics.crazyflie-uncalibrated.yaml)");
        sub->add_option("--out", options.out_dir, "output folder (physics.yaml, calibration.md/.json, pictures)")
            ->required();
        sub->add_option("--jobs", options.jobs, "flights replayed at once")->check(dw::cli::in(dw::kJobsRange));
        sub->add_option("--stride", options.stride, "every n-th near sample enters the fit")
            ->check(dw::cli::in(dw::analysis::kStrideRange))
            ->capture_default_str();
        sub->add_option("--iterations", options.max_iterations, "iterations of the fit on every trial")
            ->check(dw::cli::in(dw::analysis::kIterationsRange))
            ->capture_default_str();
        sub->add_option("--fold-iterations", options.fold_iterations, "iterations of each fit with a trial left out")
            ->check(dw::cli::in(dw::analysis::kIterationsRange))
            ->capture_default_str();
        sub->add_flag("--explain", options.explain_heldout,
                      "also explain each trial against the calibration that left it out (reports in folds/)");
        return sub;
    }
    int run() override {
        prepare(options, root.progress());
        const std::string path = physics.empty() ? root.physics_path : physics;
        options.physics = dw::physics::physics_or_defaults(path);
        const auto r = dw::analysis::calibrate(options);
        for (const auto& p : r.parameters)
            std::cout << p.vehicle_class << ": " << p.name << " " << p.value << " [" << p.lo << ", " << p.hi << "]\n";
        std::cout << "calibrated on " << r.trials.size() << " trials: " << r.physics_path << " (report "
                  << r.report_path << ", " << r.seconds << " s)\n";
        return 0;
    }
};

// `dw-explain session-proof`: rig effects concealed in every flight of sessions of recorded flights.
struct SessionProofCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    dw::analysis::SessionProofOptions options;
    std::string cases, physics;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("session-proof",
                                 "group recorded flights into sessions, conceal a rig effect in every flight below "
                                 "what one flight shows, and check the session finds it on top of its own fit");
        sub->add_option("--flights", options.flights,
                        "flight folders (those with a neighbour are grouped into sessions, in order or --interleave)")
            ->required();
        add_recorded_study_options(sub, options, physics, cases, "output folder (session_proof.md)");
        sub->add_option("--session-size", options.session_size, "flights per session")
            ->check(dw::cli::in({2, 100}))
            ->capture_default_str();
        sub->add_option("--sessions", options.max_sessions, "at most this many sessions (0: every full group)")
            ->check(dw::cli::in({0, 1000}));
        sub->add_flag("--interleave", options.interleave,
                      "deal the flights into the sessions in turn (flight k to session k mod sessions), not in order");
        return sub;
    }
    int run() override { return run_recorded_study(options, physics, root, cases, dw::analysis::run_session_proof); }
};

// `dw-explain session`: several flights of one rig explained as one session.
struct SessionCommand final : ExplainTool {
    using ExplainTool::ExplainTool;
    std::vector<std::string> flights;
    std::string out, effects, spread;
    bool rig_only = false;

    CLI::App* add(CLI::App& app) override {
        sub = app.add_subcommand("session",
                                 "explain several flights of one rig as one session: the rig's effects (clock, sensor "
                                 "lag, cross-talk, gain) fitted jointly, each flight's own effects on top");
        sub->add_option("--flights", flights, "flight folders (e.g. dw-import's), two or more")->required();
        sub->add_option("--out", out, "output folder: session.json, session.md, a report per flight")->required();
        sub->add_option("--effects", effects, "candidates, comma-separated (default: every effect of the vocabulary)");
        sub->add_flag("--rig-only", rig_only, "the rig's effects only (no per-flight explanation)");
        sub->add_option("--spread", spread,
                        "an earlier session's session.json: its between-flight spreads are this rig's natural "
                        "variation (default: none, which is strict)");
        return sub;
    }
    int run() override {
        dw::analysis::require_session_size(flights.size());  // before any flight is read
        dw::require_output_dir(out, "--out");
        dw::analysis::SessionOptions o;
        o.explain.physics = dw::physics::physics_or_defaults(root.physics_path);
        if (!effects.empty()) o.explain.candidates = dw::analysis::effects_named(split_list(effects));
        o.explain.progress = root.progress();
        o.explain.stop = dw::Shutdown::instance().token();
        o.flight_effects = !rig_only;
        if (!spread.empty()) o.between_flight_sd = dw::analysis::spreads_from(spread);
        std::vector<dw::flight::Flight> read;  // every input read before any work is done
        std::vector<std::string> names;
        for (const auto& path : flights) {
            read.push_back(dw::flight::read_flight(path));
            names.push_back(std::filesystem::path(path).filename().string());
        }
        const auto r = dw::analysis::explain_session(read, names, o);
        dw::analysis::write_session_report(read, r, o, out);
        std::cout << r.verdict << "; report: " << out << "/session.md (" << r.seconds << " s)\n";
        return 0;
    }
};

// The main command: explain one recording. It holds the root's options the others are given.
struct ExplainCommand final : dw::cli::Command {
    Root root;
    std::string real, out, effects;
    std::uint64_t seed = 1;

    CLI::App* add(CLI::App& app) override {
        app.add_option("--physics", root.physics_path,
                       "the physics configuration to compare with (default: config/physics.example.yaml's defaults)");
        app.add_option("--real", real, "the recording: a flight folder (downwash-flight/1) or an .mcap file");
        app.add_option("--out", out, "output folder: report.json, report.md, physics.yaml, figures");
        app.add_option("--effects", effects, "candidates, comma-separated (default: every effect of the vocabulary)");
        app.add_option("--seed", seed, "seed (the analysis is deterministic; recorded in the report)")
            ->check(dw::cli::in(dw::kSeedRange));
        app.add_flag("--quiet", root.quiet, "no progress");
        return &app;
    }
    int run() override {
        if (real.empty()) throw dw::InputError("--real: required (a flight folder or an .mcap recording)");
        if (out.empty()) throw dw::InputError("--out: required (the report's folder)");
        dw::require_output_dir(out, "--out");
        dw::analysis::ExplainOptions o;
        o.physics = dw::physics::physics_or_defaults(root.physics_path);
        if (!effects.empty()) o.candidates = dw::analysis::effects_named(split_list(effects));
        o.seed = seed;
        o.progress = root.progress();
        o.stop = dw::Shutdown::instance().token();
        // A recording is explained with its stamps as recorded: the explainer checks the clocks itself,
        // and the report puts the time service's measurement beside what it fits.
        dw::recordings::ExportOptions raw;
        raw.raw_stamps = true;
        raw.stop = dw::Shutdown::instance().token();
        const auto f = dw::recordings::read_flight_or_recording(real, raw);
        const auto r = dw::analysis::explain(f, o);
        dw::analysis::write_report(f, r, o, out);
        std::cout << dw::analysis::verdict_line(r) << "; report: " << out << "/report.md (" << r.seconds << " s)\n";
        return 0;
    }
};

int run(int argc, char** argv) {
    CLI::App app{
        "dw-explain: locate where a recording departs from the simulation, name the missing physics, fit it, "
        "re-simulate"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    ExplainCommand explain;
    const Root& root = explain.root;
    ProofCommand proof(root);
    UnnamedCommand unnamed(root);
    RealProofCommand real_proof(root);
    CoverageCommand coverage(root);
    CalibrateCommand calibrate(root);
    SessionCommand session(root);
    SessionProofCommand session_proof(root);
    return dw::cli::run_commands(
        app, {&explain, &proof, &unnamed, &real_proof, &coverage, &calibrate, &session, &session_proof}, [&] {
            dw::cli::parse(app, argc, argv);
            dw::log::set_level(dw::log::parse_level(base.log_level));
        });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-explain", [&] { return run(argc, argv); });
}
