// dw-predictor: learnt downwash models — train, compare, draw maps, run the whole study, and
// predict online from the motion capture.
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "plot/png.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "dds/heartbeat.hpp"
#include "dds/process_cli.hpp"
#include "flight/flight.hpp"
#include "predictor/ensemble.hpp"
#include "predictor/evaluate.hpp"
#include "predictor/maps.hpp"
#include "predictor/node.hpp"
#include "predictor/real.hpp"
#include "predictor/study.hpp"
#include "predictor/train.hpp"
#include "physics/effect_types.hpp"
#include "physics/trajectory.hpp"

namespace {

using namespace dw::predictor;

constexpr const char* kThreadsHelp =
    "libtorch threads per training (default 1: more spin against each other and any other busy process)";

constexpr const char* kStudyJobsHelp =
    "cores the study may use: flights flown at once, trainings (jobs / threads) at once (default: every core)";

constexpr const char* kMembersHelp =
    "Deep Sets trainings (each from its own seed) averaged into the model (1: one training)";

Dataset load_all(const std::vector<std::string>& paths) {
    Dataset d;
    for (const auto& p : paths) {
        dw::log::debug("reading ", p);
        d.append(load_dataset(p));
    }
    return d;
}

std::vector<const ForceModel*> raw(const std::vector<std::unique_ptr<ForceModel>>& models) {
    std::vector<const ForceModel*> out;
    for (const auto& m : models) out.push_back(m.get());
    return out;
}

void say(const std::string& line) { dw::log::progress(line); }

// The physics whose noise model (turbulence intensity, vehicle classes' floors) the intervals take:
// the first physics configuration among the model files (as loaded: `models[i]` from `paths[i]`),
// else none (no turbulence, no class floors).
dw::physics::PhysicsConfig noise_physics(const std::vector<std::string>& paths,
                                         const std::vector<std::unique_ptr<ForceModel>>& models) {
    for (std::size_t i = 0; i < paths.size(); ++i)
        if (paths[i].ends_with(".yaml") || paths[i].ends_with(".yml")) return *models[i]->physics();
    dw::physics::PhysicsConfig none;
    none.turbulence.enabled = false;
    return none;
}

// ---- one struct per subcommand: its options, how it is declared, what it does --------------------

struct StudyCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    StudyOptions so;
    std::string physics_path;
    std::vector<std::string> effects;
    bool no_generalisation = false, no_maps = false;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand(
            "study",
            "simulate flights, train every model, compare on held-out legs, draw maps (one command for the table)");
        cmd->add_option("--out", so.out_dir, "output folder (flights, models, table.md, table.csv, maps)")->required();
        cmd->add_option("--physics", physics_path,
                        "physics configuration (default: config/physics.example.yaml's defaults)");
        cmd->add_option("--effect", effects,
                        "switch an effect of the vocabulary on at its configured values (repeatable; e.g. the jets "
                        "merging: the aggregate is not a sum)");
        cmd->add_option("--legs", so.legs, "legs per flight")
            ->check(dw::cli::in(dw::Range{5, dw::physics::kLegsRange.hi}));
        cmd->add_option("--seed", so.seed, "seed of the flights and the training")->check(dw::cli::in(dw::kSeedRange));
        cmd->add_option("--epochs", so.max_epochs, "at most this many epochs per model")
            ->check(dw::cli::in(kEpochsRange));
        cmd->add_option("--threads", so.threads, kThreadsHelp)->check(dw::cli::in(kThreadsRange));
        cmd->add_option("--jobs", so.jobs, kStudyJobsHelp)->check(dw::cli::in(dw::kJobsRange));
        cmd->add_option("--members", so.members, kMembersHelp)->check(dw::cli::in(kMembersRange));
        cmd->add_option("--altitude", so.arena.altitude_m, "relative altitude of the Table 1 metric and the maps [m]")
            ->check(dw::cli::in(dw::physics::kAltitudeRange));
        cmd->add_flag("--no-generalisation", no_generalisation, "skip the K <= 2 -> K = 3 and leave-stack-out tests");
        cmd->add_flag("--no-maps", no_maps, "skip the maps");
        return cmd;
    }
    int run() override {
        so.physics = dw::physics::physics_or_defaults(physics_path);
        for (const auto& e : effects) dw::physics::effect_type(e, "--effect").switch_on(so.physics.effects);
        dw::require_output_dir(so.out_dir, "--out");
        so.generalisation = !no_generalisation;
        so.maps = !no_maps;
        so.progress = say;
        so.stop = dw::Shutdown::instance().token();
        const auto r = run_study(so);
        std::cout << "wrote " << r.markdown_path << " and " << r.csv_path << "\n";
        return 0;
    }
};

struct RegimesCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    std::string dir;
    RegimeOptions o;

    CLI::App* add(CLI::App& app) override {
        cmd =
            app.add_subcommand("regimes",
                               "the regime map of a study's folder: each formation x altitude band chaotic, linear or "
                               "non-linear on held-out legs (regimes.md, .csv, .png)");
        cmd->add_option("--study", dir, "a dw-predictor study --out folder (its flights and models)")->required();
        cmd->add_option("--min-z", o.min_z, "paired z Deep Sets must reach over the sum to call a band non-linear")
            ->check(dw::cli::in(kMinZRange));
        cmd->add_option("--min-gain", o.min_gain, "fraction of the sum's squared error Deep Sets must remove")
            ->check(dw::cli::in(kFractionRange));
        cmd->add_option("--min-explained", o.min_explained,
                        "below this fraction of f_d's mean square explained, a band is chaotic")
            ->check(dw::cli::in(kFractionRange));
        return cmd;
    }
    int run() override {
        const auto r = regimes_of_study(dir, o, dw::Shutdown::instance().token());
        std::cout << dw::read_file(r.markdown_path, "regimes") << "wrote " << r.markdown_path << ", " << r.csv_path
                  << " and " << r.png_path << "\n";
        return 0;
    }
};

struct TrainCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    TrainOptions to;
    int members = kDefaultDeepSetsMembers;
    std::vector<std::string> data;
    std::string model_out, baseline_path;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("train", "train one model on flight folders / recordings (split by leg)");
        cmd->add_option("--kind", to.kind, "naive_linear, learnt_linear or deep_sets")->required();
        cmd->add_option("--data", data, "flight folders or .mcap recordings")->required();
        cmd->add_option("--out", model_out, "model file to write (JSON)")->required();
        cmd->add_option("--epochs", to.max_epochs, "at most this many epochs")->check(dw::cli::in(kEpochsRange));
        cmd->add_option("--threads", to.threads, kThreadsHelp)->check(dw::cli::in(kThreadsRange));
        cmd->add_option("--seed", to.seed, "seed")->check(dw::cli::in(dw::kSeedRange));
        cmd->add_option("--members", members, kMembersHelp)->check(dw::cli::in(kMembersRange));
        cmd->add_option("--hidden", to.hidden, "hidden layer width")->check(dw::cli::in(kHiddenRange));
        cmd->add_option("--patience", to.patience, "epochs without a better validation loss before stopping")
            ->check(dw::cli::in(kPatienceRange));
        cmd->add_option(
            "--baseline", baseline_path,
            "deep_sets only: a saved sum model (learnt_linear) to learn the residual on, as the study does");
        return cmd;
    }
    int run() override {
        dw::require_writable_path(model_out, "--out");
        to.stop = dw::Shutdown::instance().token();
        Dataset d = load_all(data);
        dw::throw_if_stopped(to.stop, "loading the data");                // before libtorch loads (~0.4 s)
        if (to.kind == "naive_linear") d = d.from_two_vehicle_flights();  // single-neighbour data only
        const Split s = split_by_leg(d);
        require_samples(d, s.train, "training");
        require_samples(d, s.validation, "validation");
        to.split = "by block (leg or encounter): block % 5 == 1 validation, block % 5 == 0 held out, else training";
        to.progress = [](int epoch, double tl, double vl) {
            std::fprintf(stderr, "\rdw-predictor: epoch %4d  training %.4f  validation %.4f", epoch, tl, vl);
        };
        std::optional<LearntModel> baseline;
        if (!baseline_path.empty()) baseline = LearntModel::load(baseline_path);
        const auto r = train_members(s.train, s.validation, to, members, baseline ? &*baseline : nullptr,
                                     [](const std::string& line) {
                                         std::cerr << "\n";  // after the epoch line
                                         say(line);
                                     });
        r.model.save(model_out);
        std::cout << to.kind << ": " << r.epochs << " epochs (best " << r.best_epoch << ", validation "
                  << r.best_validation_loss << "), " << r.seconds << " s; wrote " << model_out << "\n";
        return 0;
    }
};

struct CompareCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    std::vector<std::string> models, data;
    std::string out_dir;
    ArenaOptions arena;
    double intensity = NAN;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand(
            "compare", "compare models on the held-out legs (leg % 5 == 0) of flights: Table 1 metric and RMSE");
        cmd->add_option("--models", models, "model files (.json), or a physics configuration (.yaml) for the simulator")
            ->required();
        cmd->add_option("--data", data, "flight folders or .mcap recordings")->required();
        cmd->add_option("--out", out_dir, "folder for table.md and table.csv")->required();
        cmd->add_option("--altitude", arena.altitude_m, "relative altitude of the arena metric [m]")
            ->check(dw::cli::in(dw::physics::kAltitudeRange));
        cmd->add_option("--turbulence-intensity", intensity,
                        "I of the 95 % intervals' noise model, sd² = floor² + (2 I prediction)² (default: the "
                        "turbulence of the first physics .yaml among --models, whose vehicle classes also give "
                        "the floors of flights where someone is always near; else 0)")
            ->check(dw::cli::in(dw::physics::kTurbulenceIntensityRange));
        return cmd;
    }
    int run() override {
        dw::require_output_dir(out_dir, "--out");
        const auto ms = load_models(models);
        const Dataset all = load_all(data);
        const Dataset test = split_by_leg(all).test;
        require_samples(all, test, "held-out");
        auto physics = noise_physics(models, ms);
        if (!std::isnan(intensity))  // the noise model of that intensity, not a calibrated one
            physics.turbulence.enabled = true, physics.turbulence.intensity = intensity, physics.prediction_noise = {};
        const auto noise = dw::predictor::noise_model(all, physics);
        const auto c = dw::predictor::compare_with_reference(raw(ms), test, arena, &noise);
        dw::write_file(out_dir + "/table.md", "# Force models compared\n\n" + c.reference_note + c.noise_note +
                                                  dw::predictor::poses_note(all) + to_markdown(c.rows, arena));
        dw::write_file(out_dir + "/table.csv", to_csv(c.rows));
        std::cout << c.reference_note << c.noise_note << to_markdown(c.rows, arena);
        return 0;
    }
};

struct RealCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    RealOptions ro;
    std::string physics_path;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand(
            "real",
            "recorded flights without legs (e.g. dw-import's): train every model, compare with the physics "
            "on held-out encounters, draw f_d by relative position");
        cmd->add_option("--data", ro.data, "flight folders or .mcap recordings")->required();
        cmd->add_option("--unseen", ro.unseen,
                        "flights (of --data) never trained on: every block held out (leave-trials-out)");
        cmd->add_option("--physics", physics_path,
                        "physics configuration (e.g. config/physics.crazyflie.yaml); vehicles come from each flight");
        cmd->add_option("--out", ro.out_dir, "output folder (models, table.md, table.csv, map_f_d.png)")->required();
        cmd->add_option("--epochs", ro.max_epochs, "at most this many epochs per model")
            ->check(dw::cli::in(kEpochsRange));
        cmd->add_option("--threads", ro.threads, kThreadsHelp)->check(dw::cli::in(kThreadsRange));
        cmd->add_option("--members", ro.members, kMembersHelp)->check(dw::cli::in(kMembersRange));
        cmd->add_option("--seed", ro.seed, "seed of the training")->check(dw::cli::in(dw::kSeedRange));
        return cmd;
    }
    int run() override {
        dw::require_output_dir(ro.out_dir, "--out");
        ro.physics = dw::physics::physics_or_defaults(physics_path);
        ro.progress = say;
        ro.stop = dw::Shutdown::instance().token();
        const auto r = run_real(ro);
        std::cout << dw::read_file(r.markdown_path, "table") << "wrote " << r.markdown_path << ", " << r.csv_path
                  << " and " << r.map_path << "\n";
        return 0;
    }
};

struct MapCommand final : dw::cli::Command {
    CLI::App* cmd = nullptr;
    MapRequest mr;
    std::vector<std::string> models, data;
    std::string axis = "f_d", png = "map.png", line;

    CLI::App* add(CLI::App& app) override {
        cmd =
            app.add_subcommand("map", "draw force maps (observed vs models, one colour scale) and a line plot along E");
        cmd->add_option("--models", models, "model files (.json) or physics configurations (.yaml)")->required();
        cmd->add_option("--formation", mr.formation,
                        "single, side_by_side, leader_follower, leader_follower3, stack or hybrid");
        cmd->add_option("--altitude", mr.altitude_m, "the formation's height above the sufferer [m]")
            ->check(dw::cli::in(dw::physics::kAltitudeRange));
        cmd->add_option("--axis", axis, dw::flight::axis_list());
        cmd->add_option("--data", data, "recorded flight of this formation: drawn as 'observed'");
        cmd->add_option("--out", png, "the map (PNG)");
        cmd->add_option("--line", line, "the line plot along E through the stand (PNG; default: <out>_line.png)");
        return cmd;
    }
    int run() override {
        mr.axis = dw::physics::axis_index(axis);
        if (mr.axis < 0) throw dw::InputError("--axis: '" + axis + "' (expected " + dw::flight::axis_list() + ")");
        (void)dw::physics::make_formation(mr.formation);  // validates the name
        if (line.empty()) line = std::filesystem::path(png).replace_extension().string() + "_line.png";
        dw::plot::require_png_path(png, "--out");
        dw::plot::require_png_path(line, "--line");
        const auto ms = load_models(models);
        if (!data.empty()) mr.observed = load_all(data);
        draw_force_map(raw(ms), mr, png);
        draw_force_line(raw(ms), mr, line);
        std::cout << "wrote " << png << " and " << line << "\n";
        return 0;
    }
};

struct OnlineCommand final : dw::cli::Command {
    explicit OnlineCommand(const dw::dds::ProcessCli& c) : cli(c) {}
    const dw::dds::ProcessCli& cli;
    CLI::App* cmd = nullptr;
    NodeOptions no;

    CLI::App* add(CLI::App& app) override {
        cmd = app.add_subcommand("run", "online: mocap/frame in, predictor/wrench out at the mocap rate");
        cmd->add_option("--model", no.model_path,
                        "model file (.json) or physics configuration (.yaml); swapped in when it changes")
            ->required();
        auto* sufferer = cmd->add_option("--sufferer", no.sufferer, "the sufferer's rigid-body name");
        cmd->add_option("--vehicles", no.vehicles_path,
                        "a flight's meta.json describing the lab's bodies (sufferer, neighbours, each one's mass and "
                        "rotors): the models take them per body, as on a recorded flight")
            ->excludes(sufferer);
        cmd->add_option("--noise", no.noise_path,
                        "physics configuration whose noise model (the sufferer's class floor, the turbulence) gives "
                        "each prediction's 95 % interval on f_d, for a learnt model (a physics model uses its own)");
        return cmd;
    }
    int run() override {
        dw::dds::Participant participant(cli.dds(), "predictor", cli.clock());
        dw::dds::Heartbeat heartbeat(participant);
        dw::SystemClock clock;
        PredictorNode node(participant, no, clock);
        heartbeat.set_state(dw::msg::PROC_RUNNING);
        while (!dw::Shutdown::instance().wait_for(std::chrono::seconds(1))) {}
        std::cout << "published " << node.published() << " predictions, " << node.reloads() << " model swaps, "
                  << node.frames_lost() << " mocap frames lost, " << node.unpredicted()
                  << " frames the model could not predict, " << node.stray_stamps()
                  << " frames refused for a stamp off the frames' time\n";
        return 0;
    }
};

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-predictor: learnt downwash force models (naive linear, learnt linear, Deep Sets)");
    CLI::App& app = cli.app();
    app.require_subcommand(1);
    StudyCommand study;
    RegimesCommand regimes;
    TrainCommand train;
    CompareCommand compare;
    RealCommand real;
    MapCommand map;
    OnlineCommand online(cli);
    return dw::cli::run_commands(app, {&study, &regimes, &train, &compare, &real, &map, &online},
                                 [&] { cli.parse(argc, argv); });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-predictor", [&] { return run(argc, argv); });
}
