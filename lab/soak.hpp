#pragma once
// `dw-lab soak`: a long simulated lab run (config/lab.sim.yaml, Leader Follower K=3, as many legs
// as fill the time) with every process's memory, CPU and losses sampled by the launcher
// (logs/resources.csv), then judged: no memory growth, no loss. Writes soak.md, soak.json and
// charts into its folder.
#include <cstdint>
#include <map>
#include <stop_token>
#include <string>
#include <vector>

#include "dds/config.hpp"
#include "lab/resources.hpp"

namespace dw::lab {

// "No growth": a process's resident memory after the warm-up may rise at most this fast.
inline constexpr double kRssSlopeLimitMbPerMin = 0.5;
// Left out of the slope: start-up allocations (the larger of the two).
inline constexpr double kWarmupS = 30;
inline constexpr double kWarmupFraction = 0.1;
inline constexpr Range kSoakMinutesRange{2, 24 * 60, "min"};
// Samples after the warm-up below which a process's memory is not judged (the verdict says so).
inline constexpr std::size_t kMinJudgedSamples = 6;

struct SoakOptions {
    double minutes = 3;
    std::string out_dir;
    std::vector<std::string> dds_args;  // for every process
    dds::DdsConfig dds;                 // the launcher's own participant
    std::stop_token stop;
};

// One process instance: a restarted process is a new instance (its own pid), judged on its own.
struct ProcessTrend {
    std::string process;
    pid_t pid = 0;
    std::size_t samples = 0, judged = 0;  // all, and those after the warm-up
    double rss_first_mb = 0, rss_last_mb = 0, rss_peak_mb = 0;
    double rss_slope_mb_per_min = 0;  // least squares over the samples after the warm-up
    double cpu_percent = 0;           // of one core, mean over the run
    std::uint64_t lost = 0;           // its readers' losses, by its last heartbeat
};

// One trend per process instance (in order of first appearance), from the launcher's rows.
std::vector<ProcessTrend> trends(const std::vector<ResourceRow>& rows);
// The verdict: "" when every process kept its memory flat and lost nothing, else why not.
std::string judge(const std::vector<ProcessTrend>& trends, std::uint64_t recorder_lost);
// Every process instance restarted is a failed soak, whatever its trend.
std::string restarts_text(const std::map<std::string, int>& restarts);

// Returns the exit code: 0 passed, 1 (dw::kExitRuntime) the run failed or the verdict is not clean.
int run_soak(const SoakOptions& o);

}  // namespace dw::lab
