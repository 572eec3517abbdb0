// dw-bench-explain: a full analysis (every candidate of the vocabulary, cross-validation,
// report and figures) of a 36-leg Leader Follower K=3 flight, with jet merging hidden and with
// nothing hidden; beside it, in the same run, simulating that flight and one resimulation pass.
//   build/bin/dw-bench-explain
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>

#include "analysis/explain.hpp"
#include "core/cli.hpp"
#include "physics/flight_sim.hpp"

using Clock = std::chrono::steady_clock;

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-explain", [&] {
        CLI::App app{"dw-bench-explain: time of a full analysis of a 36-leg K=3 flight"};
        dw::cli::BaseOptions base;
        dw::cli::configure(app, base);
        dw::cli::parse(app, argc, argv);
        const auto dir = std::filesystem::temp_directory_path() / ("dw-bench-explain-" + std::to_string(::getpid()));
        auto secs = [](Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); };
        std::printf("| step (36-leg leader_follower3, 2 cores) | seconds | target |\n|---|---|---|\n");
        for (bool merging : {true, false}) {
            dw::physics::PhysicsConfig hidden;
            if (merging) dw::physics::effect_type("jet_merging").switch_on(hidden.effects);
            dw::physics::FlyOptions fly;
            fly.formation = "leader_follower3";
            fly.seed = 7;
            auto t0 = Clock::now();
            const auto flight = dw::physics::simulate_flight(hidden, fly).flight;
            const double sim_s = secs(t0);
            t0 = Clock::now();
            const dw::analysis::Resimulation sim(flight);
            (void)sim.recorded(dw::physics::PhysicsConfig{});
            const double resim_s = secs(t0);
            dw::analysis::ExplainOptions o;
            t0 = Clock::now();
            const auto r = dw::analysis::explain(flight, o);
            dw::analysis::write_report(flight, r, o, dir.string());
            const double explain_s = secs(t0);
            std::string by;
            for (const auto& c : r.accepted) by += (by.empty() ? "" : ", ") + c.effect.name;
            const char* what = merging ? "jet merging hidden" : "nothing hidden";
            std::printf("| simulate the flight (dw-sim fly's work), %s | %.2f | (anchor) |\n", what, sim_s);
            std::printf("| one sim of it through the physics | %.2f | (anchor) |\n", resim_s);
            std::printf("| full analysis + report, %s (found: %s) | **%.1f** | <= 60 |\n", what,
                        by.empty() ? "nothing" : by.c_str(), explain_s);
        }
        std::filesystem::remove_all(dir);
        return 0;
    });
}
