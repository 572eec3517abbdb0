// dw-sim: the downwash physics simulator. `dw-sim fly` writes a simulated flight folder; `dw-sim
// replay` writes a recorded flight's wrench as a physics configuration predicts it along the
// flight's own poses (with the discrepancy dw-explain learnt, when the configuration carries one).
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "analysis/replay.hpp"
#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "flight/flight.hpp"
#include "physics/flight_sim.hpp"

namespace {

struct FlyCommand final : dw::cli::Command {
    dw::physics::FlyOptions fly;
    std::string physics_path, out_dir, altitudes;  // empty: GridOptions' own
    bool quiet = false;

    CLI::App* add(CLI::App& app) override {
        auto* cmd =
            app.add_subcommand("fly", "simulate a formation flying grid legs over the stand; write a flight folder");
        cmd->add_option("--formation", fly.formation,
                        "single, side_by_side, leader_follower, leader_follower3, stack or hybrid")
            ->required();
        cmd->add_option("--physics", physics_path,
                        "physics configuration (default: the documented defaults, config/physics.example.yaml); "
                        "a learnt discrepancy in it is added to the recorded wrench");
        cmd->add_option("--seed", fly.seed, "random seed: the same inputs and seed give the same bytes")
            ->check(dw::cli::in(dw::kSeedRange));
        cmd->add_option("--out", out_dir, "flight folder to write")->required();
        std::string defaults;
        for (double a : fly.grid.altitudes_m) defaults += (defaults.empty() ? "" : ",") + dw::log::cat(a);
        cmd->add_option("--altitudes", altitudes,
                        "relative altitudes above the sufferer [m], comma-separated (default " + defaults + ")");
        cmd->add_option("--legs", fly.grid.legs, "number of legs")->check(dw::cli::in(dw::physics::kLegsRange));
        cmd->add_option("--speed", fly.grid.speed_mps, "leg speed [m/s]")->check(dw::cli::in(dw::physics::kSpeedRange));
        cmd->add_flag("--flying-sufferer", fly.flying_sufferer.enabled,
                      "the sufferer flies (swaying about the stand's point) and its wrench is recorded as a "
                      "residual (forces only, no stand)");
        cmd->add_flag("--quiet", quiet, "no progress");
        return cmd;
    }

    int run() override {
        dw::require_output_dir(out_dir, "--out");
        if (!altitudes.empty())
            fly.grid.altitudes_m = dw::parse_number_list(altitudes, dw::physics::kAltitudeRange, "--altitudes");
        const auto physics = dw::physics::physics_or_defaults(physics_path);
        if (!quiet) {
            fly.progress = [](double done) {
                std::fprintf(stderr, "\rdw-sim: simulating %3d %%", static_cast<int>(done * 100));
                if (done >= 1.0) std::fprintf(stderr, "\n");
            };
        }
        const auto t0 = std::chrono::steady_clock::now();
        fly.stop = dw::Shutdown::instance().token();
        auto result = dw::physics::simulate_flight(physics, fly);
        if (!physics.discrepancy.empty())
            dw::analysis::add_wrench(result.flight, dw::analysis::replay(result.flight, physics).discrepancy);
        dw::flight::write_flight(result.flight, out_dir);
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        double peak = 0;
        for (const auto& s : result.flight.wrench) peak = std::max(peak, std::abs(s.w[2]));
        std::cout << "wrote " << out_dir << ": " << result.flight.meta.formation
                  << " K=" << result.flight.meta.neighbours.size() << ", " << result.flight.legs->size() << " legs, "
                  << result.truth_t.back() << " s of flight, " << result.flight.wrench.size() << " wrench samples, "
                  << result.flight.poses.size() << " poses, peak |f_d| " << peak << " N"
                  << (physics.discrepancy.empty() ? "" : ", with the learnt discrepancy") << " (" << secs << " s)\n";
        return 0;
    }
};

// One line of per-axis RMS: "f_n 0.0012 N, f_d 0.0104 N, ..." over the axes measured.
std::string rms_line(const dw::flight::AxisValues& v, const dw::analysis::Replay& r) {
    std::string out;
    for (std::size_t a = 0; a < 6; ++a)
        if (r.measured_axes[a])
            out += dw::log::cat(out.empty() ? "" : ", ", dw::flight::kAxes[a], " ", dw::fixed(v[a], 4),
                                a < 3 ? " N" : " N m");
    return out;
}

struct ReplayCommand final : dw::cli::Command {
    std::string flight_dir, physics_path, out_dir;
    bool without = false;

    CLI::App* add(CLI::App& app) override {
        auto* cmd = app.add_subcommand(
            "replay",
            "a recorded flight's wrench as a physics configuration predicts it along the flight's own poses (no "
            "noise), with its learnt discrepancy; prints how close it comes to the recording on the flight's blocks");
        cmd->add_option("--flight", flight_dir, "recorded flight folder (FLIGHT_FORMAT.md)")->required();
        cmd->add_option("--physics", physics_path, "physics configuration (e.g. a physics.yaml dw-explain wrote)");
        cmd->add_option("--out", out_dir, "flight folder to write: the flight with the replayed wrench")->required();
        cmd->add_flag("--without-discrepancy", without, "leave the configuration's learnt discrepancy out");
        return cmd;
    }

    int run() override {
        dw::require_output_dir(out_dir, "--out");
        const auto physics = dw::physics::physics_or_defaults(physics_path);
        const auto recorded = dw::flight::read_flight(flight_dir);
        const auto r = dw::analysis::replay(recorded, physics);
        const auto with = r.with_discrepancy();  // the physics alone when there is none
        std::cout << "the replay against the recording, RMS on its blocks:\n  physics alone:        "
                  << rms_line(dw::analysis::rms_on_blocks(recorded, r, r.physics), r) << "\n";
        if (!physics.discrepancy.empty()) {
            std::cout << "  with the discrepancy: " << rms_line(dw::analysis::rms_on_blocks(recorded, r, with), r)
                      << "\n";
        }
        auto f = recorded;
        dw::analysis::set_wrench(f, without ? r.physics : with);
        dw::flight::write_flight(f, out_dir);
        std::cout << "wrote " << out_dir << (physics.discrepancy.empty() || without ? "" : " (with the discrepancy)")
                  << "\n";
        return 0;
    }
};

int run(int argc, char** argv) {
    CLI::App app{"dw-sim: the downwash physics simulator (no hardware involved: everything is simulated)"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    app.require_subcommand(1);
    FlyCommand fly;
    ReplayCommand replay;
    return dw::cli::run_commands(app, {&fly, &replay}, [&] {
        dw::cli::parse(app, argc, argv);
        dw::log::set_level(dw::log::parse_level(base.log_level));
    });
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-sim", [&] { return run(argc, argv); });
}
