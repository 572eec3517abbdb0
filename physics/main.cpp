// dw-sim: the downwash physics simulator. `dw-sim fly` writes a simulated flight folder.
#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>

#include "core/cli.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "flight/flight.hpp"
#include "physics/flight_sim.hpp"

namespace {

int run(int argc, char** argv) {
    CLI::App app{"dw-sim: the downwash physics simulator (no hardware involved: everything is simulated)"};
    dw::cli::BaseOptions base;
    dw::cli::configure(app, base);
    app.require_subcommand(1);

    dw::physics::FlyOptions fly;
    std::string physics_path, out_dir, altitudes;  // empty: GridOptions' own
    bool quiet = false;
    auto* cmd =
        app.add_subcommand("fly", "simulate a formation flying grid legs over the stand; write a flight folder");
    cmd->add_option("--formation", fly.formation,
                    "single, side_by_side, leader_follower, leader_follower3, stack or hybrid")
        ->required();
    cmd->add_option("--physics", physics_path,
                    "physics configuration (default: the documented defaults, config/physics.example.yaml)");
    cmd->add_option("--seed", fly.seed, "random seed: the same inputs and seed give the same bytes")
        ->check(dw::cli::in(dw::kSeedRange));
    cmd->add_option("--out", out_dir, "flight folder to write")->required();
    std::string default_altitudes;
    for (double a : fly.grid.altitudes_m) default_altitudes += (default_altitudes.empty() ? "" : ",") + dw::log::cat(a);
    cmd->add_option("--altitudes", altitudes,
                    "relative altitudes above the sufferer [m], comma-separated (default " + default_altitudes + ")");
    cmd->add_option("--legs", fly.grid.legs, "number of legs")->check(dw::cli::in(dw::physics::kLegsRange));
    cmd->add_option("--speed", fly.grid.speed_mps, "leg speed [m/s]")->check(dw::cli::in(dw::physics::kSpeedRange));
    cmd->add_flag("--flying-sufferer", fly.flying_sufferer.enabled,
                  "the sufferer flies (swaying about the stand's point) and its wrench is recorded as a residual "
                  "(forces only, no stand)");
    cmd->add_flag("--quiet", quiet, "no progress");

    dw::cli::parse(app, argc, argv);
    dw::log::set_level(dw::log::parse_level(base.log_level));
    dw::require_output_dir(out_dir, "--out");
    if (!altitudes.empty())
        fly.grid.altitudes_m = dw::parse_number_list(altitudes, dw::physics::kAltitudeRange, "--altitudes");
    const dw::physics::PhysicsConfig physics =
        physics_path.empty() ? dw::physics::PhysicsConfig{} : dw::physics::load_physics(physics_path);
    if (!quiet) {
        fly.progress = [](double done) {
            std::fprintf(stderr, "\rdw-sim: simulating %3d %%", static_cast<int>(done * 100));
            if (done >= 1.0) std::fprintf(stderr, "\n");
        };
    }
    const auto t0 = std::chrono::steady_clock::now();
    fly.stop = dw::Shutdown::instance().token();
    const auto result = dw::physics::simulate_flight(physics, fly);
    dw::flight::write_flight(result.flight, out_dir);
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    double peak = 0;
    for (const auto& s : result.flight.wrench) peak = std::max(peak, std::abs(s.w[2]));
    std::cout << "wrote " << out_dir << ": " << result.flight.meta.formation
              << " K=" << result.flight.meta.neighbours.size() << ", " << result.flight.legs->size() << " legs, "
              << result.truth_t.back() << " s of flight, " << result.flight.wrench.size() << " wrench samples, "
              << result.flight.poses.size() << " poses, peak |f_d| " << peak << " N (" << secs << " s)\n";
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-sim", [&] { return run(argc, argv); });
}
