#pragma once
// What each lab process costs while it runs: resident memory and CPU time read from /proc, with
// the samples its heartbeat says were lost, written by `dw-lab run` every few seconds to
// logs/resources.csv — the soak's raw data (lab/soak.hpp).
#include <sys/types.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace dw::lab {

inline constexpr double kResourcePeriodS = 5.0;  // between two rows of a process
inline constexpr const char* kResourceHeader = "t_s,process,pid,rss_mb,cpu_s,lost";
inline constexpr const char* kResourceFile = "resources.csv";  // under the run's logs/

struct Usage {
    double rss_mb = 0;  // resident set now
    double cpu_s = 0;   // user + system CPU time so far
};

// Linux /proc/<pid>; nullopt once the process is gone (or elsewhere: a process started over ssh
// is measured as its local ssh client).
std::optional<Usage> usage_of(pid_t pid);

struct ResourceRow {
    double t_s = 0;  // since the launch
    std::string process;
    pid_t pid = 0;
    Usage usage;
    std::uint64_t lost = 0;  // samples lost on its readers so far (its heartbeat's count)
};

std::string to_csv_line(const ResourceRow& r);  // ended by its newline
// Reads a resources.csv; throws dw::InputError naming the file and line of a bad row.
std::vector<ResourceRow> read_resources(const std::string& path);

}  // namespace dw::lab
