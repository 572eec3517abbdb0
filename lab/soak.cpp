#include "lab/soak.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "lab/lab_sim_yaml.hpp"
#include "lab/launcher.hpp"
#include "mcap/mcap.hpp"
#include "physics/config.hpp"
#include "plot/chart.hpp"
#include "swarm_planner/experiment.hpp"
#include "swarm_planner/plan.hpp"

namespace dw::lab {

namespace fs = std::filesystem;

namespace {

constexpr const char* kFormation = "leader_follower3";
constexpr const char* kVehicles = "v1,v2,v3";  // the formation's three neighbours
constexpr double kAltitude_m = 1.3, kSpeed_mps = 0.5;

// Flown around the legs: calibration, take-off, the hold and the landing (the planner's defaults).
double around_legs_s() {
    const planner::RunOptions r;
    return r.calibrate_s + r.takeoff_s + r.hold_s + r.land_s;
}

// The fewest legs whose plan fills `minutes` (the plan's own duration; legs differ in length, so a
// search, not a rate: the first leg's transition is long).
int legs_for(double minutes) {
    auto duration = [](int legs) {
        planner::PlanOptions p;
        p.formation = kFormation;
        p.grid.legs = legs;
        p.grid.altitudes_m = {kAltitude_m};
        p.grid.speed_mps = kSpeed_mps;
        return planner::make_plan(p).duration_s() + around_legs_s();
    };
    int lo = static_cast<int>(physics::kLegsRange.lo), hi = static_cast<int>(physics::kLegsRange.hi);
    if (duration(hi) < minutes * 60)
        throw InputError(log::cat("--minutes ", minutes, ": the longest plan (", hi, " legs) lasts ",
                                  std::floor(duration(hi) / 60), " minutes"));
    while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (duration(mid) >= minutes * 60) hi = mid;
        else lo = mid + 1;
    }
    return lo;
}

// Samples the recorder stored as lost or dropped ("loss" metadata: "recorded N, lost M, ...,
// dropped (disk stalled) D").
std::uint64_t recorded_losses(const std::string& mcap_path) {
    std::uint64_t lost = 0;
    mcap::Handlers h;
    h.on_metadata = [&](const mcap::Metadata& m) {
        if (m.name != "loss") return;
        for (const auto& [topic, text] : m.entries) {
            for (const std::string what : {", lost ", ", dropped (disk stalled) "})
                if (const auto at = text.find(what); at != std::string::npos)
                    lost += std::stoull(text.substr(at + what.size()));
        }
    };
    const auto r = mcap::read_file(mcap_path, h);
    if (r.error) throw RuntimeError(log::cat(mcap_path, ": ", *r.error));
    return lost;
}

double slope_per_min(const std::vector<std::pair<double, double>>& ts) {
    if (ts.size() < 2) return 0;
    double mt = 0, mv = 0;
    for (const auto& [t, v] : ts) mt += t, mv += v;
    mt /= static_cast<double>(ts.size());
    mv /= static_cast<double>(ts.size());
    double num = 0, den = 0;
    for (const auto& [t, v] : ts) num += (t - mt) * (v - mv), den += (t - mt) * (t - mt);
    return den > 0 ? num / den * 60.0 : 0.0;
}

}  // namespace

std::vector<ProcessTrend> trends(const std::vector<ResourceRow>& rows) {
    const double end = rows.empty() ? 0 : rows.back().t_s;
    const double warmup = std::max(kWarmupS, kWarmupFraction * end);
    using Instance = std::pair<std::string, pid_t>;
    std::vector<Instance> order;
    std::map<Instance, std::vector<const ResourceRow*>> by;
    for (const auto& r : rows) {
        const Instance key{r.process, r.pid};
        if (!by.count(key)) order.push_back(key);
        by[key].push_back(&r);
    }
    std::vector<ProcessTrend> out;
    for (const auto& key : order) {
        const auto& v = by[key];
        ProcessTrend p{key.first, key.second, v.size(),      0, v.front()->usage.rss_mb, v.back()->usage.rss_mb, 0,
                       0,         0,          v.back()->lost};
        std::vector<std::pair<double, double>> late;
        for (const auto* r : v) {
            p.rss_peak_mb = std::max(p.rss_peak_mb, r->usage.rss_mb);
            if (r->t_s >= warmup) late.emplace_back(r->t_s, r->usage.rss_mb);
        }
        p.judged = late.size();
        p.rss_slope_mb_per_min = slope_per_min(late);
        const double span = v.back()->t_s - v.front()->t_s;
        p.cpu_percent = span > 0 ? 100.0 * (v.back()->usage.cpu_s - v.front()->usage.cpu_s) / span : 0.0;
        out.push_back(p);
    }
    return out;
}

std::string restarts_text(const std::map<std::string, int>& restarts) {
    std::string why;
    for (const auto& [process, n] : restarts)
        why += log::cat(why.empty() ? "" : "; ", process, " restarted ", n, " time(s)");
    return why;
}

std::string judge(const std::vector<ProcessTrend>& trends, std::uint64_t recorder_lost) {
    std::string why;
    auto add = [&](const std::string& s) { why += (why.empty() ? "" : "; ") + s; };
    for (const auto& p : trends) {
        if (p.judged < kMinJudgedSamples)
            add(log::cat(p.process, " (pid ", p.pid, "): ", p.judged,
                         " samples after the warm-up, too few to judge its memory"));
        else if (!(p.rss_slope_mb_per_min <= kRssSlopeLimitMbPerMin))
            add(log::cat(p.process, "'s memory grows ", p.rss_slope_mb_per_min, " MB/min (limit ",
                         kRssSlopeLimitMbPerMin, ")"));
        if (p.lost > 0) add(log::cat(p.process, " lost ", p.lost, " samples"));
    }
    if (recorder_lost > 0) add(log::cat("the recording is missing ", recorder_lost, " samples"));
    if (trends.empty()) add("no process was measured");
    return why;
}

namespace {

void write_charts(const std::vector<ResourceRow>& rows, const fs::path& dir) {
    static const std::array<std::array<unsigned char, 3>, 6> kColours{
        {{200, 80, 0}, {0, 140, 0}, {0, 0, 200}, {160, 0, 160}, {0, 140, 200}, {90, 90, 90}}};
    std::map<std::string, std::size_t> index;
    plot::Chart rss{"Resident memory of each lab process (dw-lab soak)", "time since launch [s]", "RSS [MB]", {}, {}};
    plot::Chart cpu{"CPU of each lab process, between two samples (dw-lab soak)",
                    "time since launch [s]",
                    "CPU [% of one core]",
                    {},
                    {}};
    std::map<std::string, const ResourceRow*> previous;
    for (const auto& r : rows) {
        auto [it, fresh] = index.try_emplace(r.process, index.size());
        if (fresh) {
            rss.series.push_back({r.process, {}, {}, kColours[it->second % kColours.size()]});
            cpu.series.push_back({r.process, {}, {}, kColours[it->second % kColours.size()]});
        }
        rss.series[it->second].x.push_back(r.t_s);
        rss.series[it->second].y.push_back(r.usage.rss_mb);
        if (const auto* p = previous[r.process]; p && r.t_s > p->t_s) {
            cpu.series[it->second].x.push_back(r.t_s);
            cpu.series[it->second].y.push_back(100.0 * (r.usage.cpu_s - p->usage.cpu_s) / (r.t_s - p->t_s));
        }
        previous[r.process] = &r;
    }
    plot::render_chart(rss, (dir / "soak_rss.png").string());
    plot::render_chart(cpu, (dir / "soak_cpu.png").string());
}

void write_reports(const std::vector<ProcessTrend>& t, std::uint64_t recorder_lost, const std::string& verdict,
                   double minutes, double lasted_s, const LaunchResult& run, const fs::path& dir) {
    std::ostringstream md;
    md << "# Soak: " << minutes << " minutes of the simulated lab (" << kFormation << ", " << run.legs_flown << " of "
       << run.legs_total << " legs, " << (run.phase.empty() ? "no state" : run.phase) << "; sampled for "
       << lasted_s / 60 << " min)\n\n"
       << "Sampled every " << kResourcePeriodS
       << " s by dw-lab run (logs/resources.csv); the slope leaves out the first " << kWarmupS << " s or "
       << kWarmupFraction * 100 << " % of the run, whichever is longer.\n\n"
       << "| process | samples after warm-up | RSS first MB | RSS last MB | RSS peak MB | RSS slope after warm-up "
          "MB/min | CPU % of a core | lost |\n"
       << "|---|---|---|---|---|---|---|---|\n";
    nlohmann::json j{{"minutes", minutes},
                     {"sampled_s", lasted_s},
                     {"phase", run.phase},
                     {"legs_flown", run.legs_flown},
                     {"recorder_lost", recorder_lost},
                     {"rss_slope_limit_mb_per_min", kRssSlopeLimitMbPerMin},
                     {"verdict", verdict.empty() ? "pass" : verdict}};
    char line[256];
    for (const auto& p : t) {
        std::snprintf(line, sizeof line, "| %s | %zu | %.1f | %.1f | %.1f | %+.3f | %.1f | %llu |\n", p.process.c_str(),
                      p.judged, p.rss_first_mb, p.rss_last_mb, p.rss_peak_mb, p.rss_slope_mb_per_min, p.cpu_percent,
                      static_cast<unsigned long long>(p.lost));
        md << line;
        j["processes"].push_back({{"process", p.process},
                                  {"pid", p.pid},
                                  {"samples", p.samples},
                                  {"judged", p.judged},
                                  {"rss_first_mb", p.rss_first_mb},
                                  {"rss_last_mb", p.rss_last_mb},
                                  {"rss_peak_mb", p.rss_peak_mb},
                                  {"rss_slope_mb_per_min", p.rss_slope_mb_per_min},
                                  {"cpu_percent", p.cpu_percent},
                                  {"lost", p.lost}});
    }
    md << "\nRecording: " << recorder_lost << " samples missing (the recorder's loss metadata).\n\n"
       << "Verdict: " << (verdict.empty() ? "pass (no memory growth, no loss)" : verdict) << "\n\n"
       << "![RSS](soak_rss.png)\n\n![CPU](soak_cpu.png)\n";
    write_file((dir / "soak.md").string(), md.str());
    write_file((dir / "soak.json").string(), j.dump(2) + "\n");
}

}  // namespace

int run_soak(const SoakOptions& o) {
    const fs::path dir = o.out_dir;
    fs::create_directories(dir);
    const std::string physics_path = (dir / "physics.yaml").string();
    write_file(physics_path, physics::to_yaml(physics::PhysicsConfig{}));
    write_file((dir / "lab.yaml").string(), kLabSimYaml);
    const int legs = legs_for(o.minutes);
    std::cerr << "dw-lab soak: " << o.minutes << " minutes: " << legs << " legs of " << kFormation << " at "
              << kAltitude_m << " m\n";
    LaunchOptions lo;
    lo.run_dir = (dir / "lab").string();
    lo.vars = {{"formation", kFormation},
               {"vehicles", kVehicles},
               {"legs", std::to_string(legs)},
               {"altitudes", log::cat(kAltitude_m)},
               {"speed", log::cat(kSpeed_mps)},
               {"physics", physics_path},
               {"model", physics_path},
               {"recording", "soak.mcap"},
               {"run_id", "soak"}};
    lo.dds_args = o.dds_args;
    lo.live = false;
    lo.say = [](const std::string& s) { std::cerr << "dw-lab: " << s << "\n"; };
    lo.stop = o.stop;
    const LaunchResult run = launch(load_lab((dir / "lab.yaml").string()), lo, o.dds);
    throw_if_stopped(o.stop, "the soak");
    std::vector<ResourceRow> rows;
    std::uint64_t recorder_lost = 0;
    try {  // made by this run: a problem with them is the run's failure, not bad input
        rows = read_resources((fs::path(lo.run_dir) / "logs" / kResourceFile).string());
        recorder_lost = recorded_losses((fs::path(lo.run_dir) / "soak.mcap").string());
    } catch (const InputError& e) {
        throw RuntimeError(
            log::cat("the soak's run left no usable record: ", e.what(), " (logs in ", lo.run_dir, "/logs)"));
    }
    const auto t = trends(rows);
    std::string verdict = judge(t, recorder_lost);
    if (const auto r = restarts_text(run.restarts); !r.empty()) verdict = r + (verdict.empty() ? "" : "; " + verdict);
    if (!run.succeeded()) verdict = log::cat("the experiment ended ", run.phase, "; ", verdict);
    write_charts(rows, dir);
    write_reports(t, recorder_lost, verdict, o.minutes, rows.empty() ? 0.0 : rows.back().t_s, run, dir);
    std::cout << read_file((dir / "soak.md").string());
    if (!verdict.empty()) std::cerr << "dw-lab soak: FAILED: " << verdict << "\n";
    return verdict.empty() ? 0 : kExitRuntime;
}

}  // namespace dw::lab
