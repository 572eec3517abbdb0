#include "lab/demo.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <thread>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "lab/lab_sim_yaml.hpp"
#include "lab/launcher.hpp"
#include "physics/config.hpp"

namespace dw::lab {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// m:ss
std::string minutes(double seconds) {
    const int s = static_cast<int>(seconds);
    return log::cat(s / 60, ":", s % 60 < 10 ? "0" : "", s % 60);
}

// The demo's steps, each announced with the time elapsed; a step may run beside others (the
// training beside the flying). Where the time went is kept for the end.
class Steps {
public:
    Steps(int total, Clock::time_point start) : total_(total), start_(start) {}
    std::size_t begin(const std::string& what) {
        const double t = seconds_since(start_);
        steps_.push_back({what, t, -1});
        std::cerr << "\n== [" << steps_.size() << "/" << total_ << "] " << what << "  (" << minutes(t) << " elapsed)\n";
        return steps_.size() - 1;
    }
    void end(std::size_t step) { steps_.at(step).end = seconds_since(start_); }
    // Each step begun, with its seconds (one not ended: up to now).
    std::vector<std::pair<std::string, double>> durations() const {
        std::vector<std::pair<std::string, double>> out;
        for (const auto& s : steps_) out.emplace_back(s.what, (s.end < 0 ? seconds_since(start_) : s.end) - s.begin);
        return out;
    }

private:
    struct Step {
        std::string what;
        double begin, end;  // seconds into the demo (end < 0: running)
    };
    int total_;
    Clock::time_point start_;
    std::vector<Step> steps_;
};

std::string first_line_with(const std::string& text, const std::string& needle) {
    const auto p = text.find(needle);
    if (p == std::string::npos) return "";
    const auto e = text.find('\n', p);
    return text.substr(p, e == std::string::npos ? std::string::npos : e - p);
}

struct DemoFlight {
    std::string name, formation, vehicles, legs, altitudes;
    std::string stand_clock_offset = "0";  // s: the running stand agent's clock error (the hidden effect)
};

// The training runs beside the real-time flying, this much nicer: the flying's processes come first.
constexpr int kTrainingNiceness = 10;

// The effect the demo hides in the running lab: the stand agent's clock 0.1 s ahead of the others'.
constexpr const char* kHiddenStandClockOffsetS = "0.1";

// 1-2. Two experiments, every process separate, over loopback DDS; each recording exported to a flight.
std::vector<LaunchResult> fly_experiments(const DemoOptions& o, const fs::path& run, const LabFile& lab,
                                          const std::string& physics_path, const std::vector<DemoFlight>& flights,
                                          Steps& steps) {
    std::vector<LaunchResult> results;
    for (std::size_t k = 0; k < flights.size(); ++k) {
        const auto& f = flights[k];
        const auto step = steps.begin(log::cat("flying ", f.formation, ": ", f.legs, " legs at ", f.altitudes,
                                               " m over loopback DDS (stand, mocap and vehicles simulated)"));
        LaunchOptions lo;
        lo.run_dir = (run / ("lab-" + f.name)).string();
        lo.vars = {{"formation", f.formation},
                   {"vehicles", f.vehicles},
                   {"legs", f.legs},
                   {"altitudes", f.altitudes},
                   {"speed", "0.5"},
                   {"physics", physics_path},
                   {"model", physics_path},
                   {"recording", "../recordings/" + f.name + ".mcap"},
                   {"run_id", "demo-" + f.name},
                   {"stand_clock_offset", f.stand_clock_offset}};
        fs::create_directories(run / "recordings");
        lo.dds_args = o.dds_args;
        lo.say = [](const std::string& s) { std::cerr << "dw-lab: " << s << "\n"; };
        lo.stop = o.stop;
        auto r = launch(lab, lo, o.dds);
        throw_if_stopped(o.stop, "the demo");
        if (!r.succeeded())
            throw RuntimeError(log::cat("the ", f.formation, " experiment ended ",
                                        r.phase.empty() ? "without a state" : r.phase, " (status ", r.experiment_status,
                                        "; logs in ", lo.run_dir, "/logs)"));
        results.push_back(r);
        run_sibling({"dw-recorder", "export", (run / "recordings" / (f.name + ".mcap")).string(), "--flight",
                     (run / "flights" / f.name).string()},
                    (run / "logs" / ("export-" + f.name + ".log")).string(), o.stop);
        steps.end(step);
    }
    return results;
}

// The lab live while the experiments fly (issue 72): dw-viewer beside them, its address printed.
// A viewer that cannot start (its port taken, say) is said in one line and the demo goes on.
constexpr int kViewerStartPolls = 500;  // of 20 ms
std::optional<Subprocess> start_viewer(const DemoOptions& o, const fs::path& run) {
    std::vector<std::string> argv{executable_dir() + "/dw-viewer", "--port", std::to_string(o.viewer_port)};
    argv.insert(argv.end(), o.dds_args.begin(), o.dds_args.end());
    const auto out = (run / "logs" / "viewer.out").string(), log_file = (run / "logs" / "viewer.log").string();
    Subprocess viewer({argv, out, log_file, {}});
    for (int i = 0; i < kViewerStartPolls && viewer.running(); ++i) {
        const auto text = fs::exists(out) ? read_file(out) : std::string();
        const auto at = text.find("viewer at ");
        if (at != std::string::npos && text.find('\n', at) != std::string::npos) {
            const auto url = text.substr(at + 10, text.find('\n', at) - at - 10);
            std::cout << "watch the lab live: open " << url << " in a browser; in Foxglove or Lichtblick, Open "
                      << "connection, Foxglove WebSocket, ws://" << url.substr(7, url.size() - 8) << std::endl;
            return viewer;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::cerr << "dw-lab: the viewer did not start (" << last_line_of(log_file) << "); the demo goes on without it\n";
    return std::nullopt;
}

// 4. The study's models on the recorded (DDS) flights, and the recorded map.
void models_on_recorded(const fs::path& run, const std::string& physics_path, const std::stop_token& stop) {
    const std::string models = (run / "study" / "models").string();
    std::vector<std::string> model_files{physics_path, models + "/naive_linear.json", models + "/learnt_linear.json",
                                         models + "/deep_sets.json"};
    std::vector<std::string> cmp{"dw-predictor", "compare", "--models"};
    cmp.insert(cmp.end(), model_files.begin(), model_files.end());
    cmp.insert(cmp.end(), {"--data", (run / "flights" / "single").string(), (run / "flights" / "lf3").string(), "--out",
                           (run / "recorded").string()});
    run_sibling(cmp, (run / "logs" / "compare.log").string(), stop);
    std::vector<std::string> map{"dw-predictor", "map", "--models"};
    map.insert(map.end(), model_files.begin(), model_files.end());
    map.insert(map.end(), {"--formation", "leader_follower3", "--altitude", "1.3", "--data",
                           (run / "flights" / "lf3").string(), "--out", (run / "recorded" / "lf3_map.png").string()});
    run_sibling(map, (run / "logs" / "map.log").string(), stop);
}

// What report.json says was found: the effects, and each accepted one's values with intervals.
std::pair<std::string, std::string> found_and_fitted(const nlohmann::json& report) {
    std::string found;
    for (const auto& e : report["explained_by"]) found += (found.empty() ? "" : ", ") + e.get<std::string>();
    auto rounded = [](const nlohmann::json& v) { return std::round(v.get<double>() * 1e4) / 1e4; };
    std::string fitted;
    for (const auto& c : report["candidates"]) {
        if (!c["accepted"].get<bool>()) continue;
        fitted += c["effect"].get<std::string>() + ":";
        for (const auto& [k, v] : c["params"].items()) {
            fitted += " " + k + " = " + (v.is_number() ? log::cat(rounded(v)) : v.dump());
            if (c["ci95"].contains(k) && c["ci95"][k].size() == 2 && c["ci95"][k][0].is_number())
                fitted += log::cat(" [", rounded(c["ci95"][k][0]), ", ", rounded(c["ci95"][k][1]), "]");
        }
        fitted += "\n";
    }
    return {found, fitted};
}

// Where the demo's time went, step by step (a markdown table).
std::string time_table(const std::vector<std::pair<std::string, double>>& steps) {
    std::string md = "## Where the time went\n\n| step | time (m:ss) |\n|---|---|\n";
    for (const auto& [what, s] : steps) md += log::cat("| ", what, " | ", minutes(s), " |\n");
    return md;
}

// 6. index.md: what ran, where its outputs are, what was found, and where the time went.
std::string index_markdown(double seconds, const std::vector<DemoFlight>& flights,
                           const std::vector<LaunchResult>& results, const nlohmann::json& report,
                           const std::vector<std::pair<std::string, double>>& steps) {
    const auto [found, fitted] = found_and_fitted(report);
    const double before = report["fit"]["heldout_rmse_before"]["f_d"].get<double>(),
                 after = report["fit"]["heldout_rmse_after"]["f_d"].get<double>();
    std::ostringstream md;
    md << "# Downwash Lab demo run\n\nEverything here is **simulated** (stand, motion capture, vehicles and the air), "
          "made by "
          "`dw-lab demo` in "
       << static_cast<int>(seconds) / 60 << " min " << static_cast<int>(seconds) % 60 << " s.\n\n";
    md << "## 1. Experiments over DDS\n\nEach experiment ran the lab file [lab.yaml](lab.yaml): recorder, stand agent "
          "(`--sim`: the "
          "emulated HX711s driven by the physics), mocap bridge (`--sim`: an emulated NatNet server), online predictor "
          "and planner, "
          "each a separate process on loopback DDS.\n\n| experiment | result | recording | flight folder | logs "
          "|\n|---|---|---|---|---|\n";
    for (std::size_t k = 0; k < flights.size(); ++k)
        md << "| " << flights[k].formation << " | " << results[k].phase << ", " << results[k].legs_flown << " of "
           << results[k].legs_total << " legs | [recordings/" << flights[k].name << ".mcap](recordings/"
           << flights[k].name << ".mcap) | [flights/" << flights[k].name << "](flights/" << flights[k].name
           << ") | [lab-" << flights[k].name << "/logs](lab-" << flights[k].name << "/logs) |\n";
    md << "\n## 2. Models and the comparison\n\nTrained by `dw-predictor study` on simulated flights of every "
          "formation (split by leg): "
          "[study/table.md](study/table.md) ([csv](study/table.csv)); models in [study/models](study/models). On the "
          "recorded "
          "DDS flights (held-out legs): [recorded/table.md](recorded/table.md).\n\n";
    md << "![Leader Follower K=3 at 1.3 m: observed, physics and the models](study/maps/leader_follower3.png)\n\n"
       << "![Along E through the stand](study/maps/leader_follower3_line.png)\n\n"
       << "The recorded Leader Follower K=3 experiment against the models:\n\n![recorded](recorded/lf3_map.png)\n\n";
    const auto measured_value = [&](const char* key) {
        const auto m = report.find("clock_offset_measured");
        return m != report.end() && m->contains(key) ? (*m)[key].get<double>() : NAN;
    };
    const double measured = measured_value("offset_s"), delay = measured_value("pipeline_delay_s"),
                 expected = measured_value("expected_s");
    auto shown = [](double v) {
        return std::isnan(v) ? std::string("not measured") : log::cat(std::round(v * 1e4) / 1e4, " s");
    };
    md << "## 3. The explained mismatch\n\nThe Leader Follower K=3 experiment ran with its stand agent's clock "
       << kHiddenStandClockOffsetS
       << " s ahead (`--clock-offset`, a simulated clock error the lab's physics does not know). `dw-explain` read its "
          "recording "
          "([recordings/lf3.mcap](recordings/lf3.mcap), stamps as recorded) with the lab's physics. Found: **"
       << (found.empty() ? "nothing" : found) << "**.\n\n```\n"
       << fitted
       << "```\n\nWhat the fitted offset estimates: the time between a force and the pose behind it "
          "beyond what the resimulation models, i.e. the stand's clock error plus the stand's own pipeline delay. "
          "The lab's time service measured the clock live: "
       << shown(measured) << "; the stand measured its pipeline delay (the simulated air acts on the poses it is "
       << "given, which arrive late): " << shown(delay) << "; together " << shown(expected) << ".\n\nHeld-out f_d RMSE "
       << std::round(before * 1000) / 1000 << " N → " << std::round(after * 1000) / 1000
       << " N. Report: [explain/report.md](explain/report.md) ([report.json](explain/report.json), fitted physics "
          "[explain/physics.yaml](explain/physics.yaml)).\n\n![residuals before](explain/residuals_before.png)\n\n"
          "![residuals after](explain/residuals_after.png)\n\n"
       << time_table(steps);
    return md.str();
}

}  // namespace

int run_demo(const DemoOptions& o) {
    const auto started = Clock::now();
    const fs::path run = fs::absolute(o.out_dir);
    fs::create_directories(run / "logs");
    Steps steps(6, started);

    // The physics every simulated part shares (config/physics.demo.yaml).
    const physics::PhysicsConfig physics = physics::parse_physics(kDemoPhysicsYaml, kDemoPhysicsSource);
    const std::string physics_path = (run / "physics.yaml").string();
    write_file(physics_path, physics::to_yaml(physics));
    const std::string lab_path = (run / "lab.yaml").string();
    write_file(lab_path, kLabSimYaml);
    const LabFile lab = load_lab(lab_path);

    const std::vector<DemoFlight> flights{
        {"single", "single", "v1", o.quick ? "3" : "9", "0.3,0.8,1.3"},
        // The explainer's cross-validation needs at least 5 blocks (encounters): 6 legs in --quick.
        {"lf3", "leader_follower3", "v1,v2,v3", o.quick ? "6" : "12", "1.3", kHiddenStandClockOffsetS},
    };
    // 3. Training and the comparison (the study: simulated training flights of every formation), on
    // the cores the real-time flying leaves idle.
    const auto training = steps.begin(
        "training naive linear, learnt linear and Deep Sets; the comparison table and maps (beside the flying)");
    std::vector<std::string> study_args{"dw-predictor", "study",      "--out",  (run / "study").string(),
                                        "--physics",    physics_path, "--jobs", std::to_string(o.jobs)};
    if (o.quick) study_args.insert(study_args.end(), {"--legs", "20", "--epochs", "30", "--no-generalisation"});
    Sibling study(study_args, (run / "logs" / "study.log").string(), kTrainingNiceness, o.stop);

    auto viewer = start_viewer(o, run);
    const std::vector<LaunchResult> results = fly_experiments(o, run, lab, physics_path, flights, steps);
    if (viewer) viewer->stop();

    // 4. Explain the recording in which the running lab hid something its physics leaves out.
    auto step = steps.begin(log::cat("explaining the Leader Follower K=3 recording (its stand agent ran ",
                                     kHiddenStandClockOffsetS, " s ahead) against the lab's physics"));
    run_sibling({"dw-explain", "--physics", physics_path, "--real", (run / "recordings" / "lf3.mcap").string(), "--out",
                 (run / "explain").string()},
                (run / "logs" / "explain.log").string(), o.stop);
    steps.end(step);

    study.finish(o.stop);
    steps.end(training);
    step = steps.begin("the models on the recorded flights: table and maps");
    models_on_recorded(run, physics_path, o.stop);
    steps.end(step);

    step = steps.begin("writing index.md");
    const auto report = nlohmann::json::parse(read_file((run / "explain" / "report.json").string()));
    steps.end(step);
    const double seconds = seconds_since(started);
    const auto time_by_step = steps.durations();
    write_file((run / "index.md").string(), index_markdown(seconds, flights, results, report, time_by_step));
    const std::string found = found_and_fitted(report).first;
    std::cout << "demo done in " << static_cast<int>(seconds) << " s: " << (run / "index.md").string() << "\n"
              << "  experiments: " << results[0].phase << ", " << results[1].phase
              << "; explained by: " << (found.empty() ? "nothing" : found) << "\n  "
              << first_line_with(read_file((run / "study" / "table.md").string()), "| leader_follower K=3") << "\n"
              << "  where the time went:\n";
    for (const auto& [what, s] : time_by_step) std::cout << "    " << minutes(s) << "  " << what << "\n";
    return 0;
}

}  // namespace dw::lab
