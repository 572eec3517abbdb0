// dw-bench-real: real flights. The import rate (MB of log per second, CSV and binary) beside `cat`
// of the same files in the same run, and a full explain (every candidate, cross-validation by
// encounter, report and figures) of the 64 s random walk beside one resimulation pass of it; and the
// calibration of every trial of two vehicles or more (on 2 cores and on one) beside one sim
// pass of every flight.
//   build/bin/dw-bench-real [--data DIR] [--physics FILE]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "analysis/calibrate.hpp"
#include "analysis/explain.hpp"
#include "core/cli.hpp"
#include "core/errors.hpp"
#include "importer/neural_swarm.hpp"

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

double secs(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

template <class F>
double median_of(int runs, F&& f) {
    std::vector<double> t;
    for (int i = 0; i < runs; ++i) {
        const auto t0 = Clock::now();
        f();
        t.push_back(secs(t0));
    }
    std::sort(t.begin(), t.end());
    return t[t.size() / 2];
}

// Every trial of two vehicles or more imported into `dir`, then calibrated as the README does.
void bench_calibration(const std::string& data, const fs::path& dir) {
    dw::analysis::CalibrateOptions o;
    for (const auto& t : dw::importer::collection_trials(data)) {
        if (t.logs.size() < 2) continue;
        const std::string folder = (dir / t.name).string();
        dw::flight::write_flight(dw::importer::neural_swarm_importer().import(t.logs, {}), folder);
        o.flights.push_back(folder);
    }
    o.physics = dw::physics::load_physics(std::string(DW_SOURCE_DIR) + "/config/physics.crazyflie-uncalibrated.yaml");
    auto t0 = Clock::now();
    for (const auto& f : o.flights)
        (void)dw::analysis::Resimulation(dw::flight::read_flight(f), o.physics).recorded(o.physics);
    const double resim_s = secs(t0);
    std::printf("\n| step (%zu trials, the README's calibrate) | seconds |\n|---|---|\n", o.flights.size());
    std::printf("| read and sim every flight once (anchor) | %.2f |\n", resim_s);
    for (int jobs : {2, 1}) {
        o.jobs = jobs;
        o.out_dir = (dir / ("calibration-" + std::to_string(jobs))).string();
        t0 = Clock::now();
        const auto r = dw::analysis::calibrate(o);
        std::printf("| dw-explain calibrate, --jobs %d (%zu parameters, each trial left out) | **%.1f** |\n", jobs,
                    r.parameters.size(), secs(t0));
    }
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-real", [&] {
        CLI::App app{"dw-bench-real: import rate beside cat, and explain on the 64 s random walk"};
        dw::cli::BaseOptions base;
        dw::cli::configure(app, base);
        std::string data =
            std::string(DW_SOURCE_DIR) + "/../shared/data/neural-swarm/data/training/datacollection21_06_16_2020";
        std::string physics = std::string(DW_SOURCE_DIR) + "/config/physics.crazyflie.yaml";
        app.add_option("--data", data, "the Neural-Swarm collection's folder");
        app.add_option("--physics", physics, "physics configuration for the explain");
        dw::cli::parse(app, argc, argv);
        if (!fs::is_directory(data))
            throw dw::InputError("--data " + data + ": not a folder (the shared Neural-Swarm logs)");
        std::vector<std::string> csv, binary;
        std::uintmax_t csv_bytes = 0, bin_bytes = 0;
        for (const auto& e : fs::recursive_directory_iterator(data)) {
            if (!e.is_regular_file()) continue;
            const bool is_csv = e.path().extension() == ".csv";
            (is_csv ? csv : binary).push_back(e.path().string());
            (is_csv ? csv_bytes : bin_bytes) += e.file_size();
        }
        std::printf("| step (2 cores) | MB | seconds (median of 5) | MB/s |\n|---|---|---|---|\n");
        for (const auto& [files, bytes, what] :
             {std::tuple{&csv, csv_bytes, "CSV logs"}, std::tuple{&binary, bin_bytes, "binary logs"}}) {
            std::string cat = "cat";
            for (const auto& f : *files) cat += " '" + f + "'";
            cat += " > /dev/null";
            const double t_cat = median_of(5, [&] {
                if (std::system(cat.c_str()) != 0) throw dw::RuntimeError("cat failed");
            });
            const double t_read = median_of(5, [&] {
                for (const auto& f : *files) (void)dw::importer::read_neural_swarm_log(f);
            });
            const double mb = static_cast<double>(bytes) / 1e6;
            std::printf("| `cat` of the %zu %s (anchor) | %.2f | %.4f | %.0f |\n", files->size(), what, mb, t_cat,
                        mb / t_cat);
            std::printf("| decode the %s (checksums, units, quaternions) | %.2f | %.4f | **%.0f** |\n", what, mb,
                        t_read, mb / t_read);
        }
        const std::vector<std::string> walk{data + "/randomwalk_ss/cf50_02", data + "/randomwalk_ss/cf51_02"};
        const double t_import = median_of(5, [&] { (void)dw::importer::neural_swarm_importer().import(walk, {}); });
        const auto flight = dw::importer::neural_swarm_importer().import(walk, {});
        std::printf(
            "| import the 64 s random walk (2 binary logs: decode, align, residual force, NED) | – | %.4f | – |\n\n",
            t_import);

        dw::analysis::ExplainOptions o;
        o.physics = dw::physics::load_physics(physics);
        auto t0 = Clock::now();
        const dw::analysis::Resimulation sim(flight, o.physics);
        (void)sim.recorded(o.physics);
        const double resim_s = secs(t0);
        const auto dir = fs::temp_directory_path() / ("dw-bench-real-" + std::to_string(::getpid()));
        t0 = Clock::now();
        const auto r = dw::analysis::explain(flight, o);
        dw::analysis::write_report(flight, r, o, dir.string());
        const double explain_s = secs(t0);
        fs::remove_all(dir);
        std::string by;
        for (const auto& c : r.accepted) by += (by.empty() ? "" : ", ") + c.effect.name;
        std::printf("| step (64 s random walk, %zu wrench samples, 2 cores) | seconds | target |\n|---|---|---|\n",
                    flight.wrench.size());
        std::printf("| one sim of it through the physics (anchor) | %.2f | – |\n", resim_s);
        std::printf("| full dw-explain + report (%zu blocks by %s; found: %s) | **%.1f** | <= 30 |\n", r.legs,
                    dw::flight::to_string(r.blocks), by.empty() ? "nothing" : by.c_str(), explain_s);
        bench_calibration(data, dir);
        fs::remove_all(dir);
        return 0;
    });
}
