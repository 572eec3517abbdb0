#include "lab/resources.hpp"

#include <unistd.h>

#include <fstream>
#include <sstream>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/text.hpp"

namespace dw::lab {

namespace {

// A run's seconds to 0.1 s for over a day.
constexpr int kTimeDigits = 7;
// /proc/<pid>/stat fields 14 and 15 (utime, stime, in clock ticks), after the command in parentheses.
std::optional<double> cpu_seconds(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto close = text.rfind(')');
    if (close == std::string::npos) return std::nullopt;
    std::istringstream rest(text.substr(close + 2));
    std::string field;
    unsigned long long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && rest >> field; ++i) {
        if (i == 14) utime = std::stoull(field);
        if (i == 15) stime = std::stoull(field);
    }
    if (!rest) return std::nullopt;
    return static_cast<double>(utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

std::optional<double> rss_mb(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/status");
    for (std::string line; std::getline(in, line);) {
        if (line.rfind("VmRSS:", 0) != 0) continue;
        return std::stod(line.substr(6)) / 1024.0;  // kB
    }
    return std::nullopt;
}
}  // namespace

std::optional<Usage> usage_of(pid_t pid) {
    const auto cpu = cpu_seconds(pid);
    const auto rss = rss_mb(pid);
    if (!cpu || !rss) return std::nullopt;
    return Usage{*rss, *cpu};
}

std::string to_csv_line(const ResourceRow& r) {
    return CsvRow()
        .num(r.t_s, kTimeDigits)
        .text(r.process)
        .count(r.pid)
        .num(r.usage.rss_mb)
        .num(r.usage.cpu_s)
        .count(static_cast<long long>(r.lost))
        .line();
}

std::vector<ResourceRow> read_resources(const std::string& path) {
    std::ifstream in(path);
    if (!in) throw InputError(log::cat(path, ": cannot read"));
    std::vector<ResourceRow> rows;
    std::string line;
    if (!std::getline(in, line) || line != kResourceHeader)
        throw InputError(log::cat(path, ":1: expected the header ", kResourceHeader));
    for (int n = 2; std::getline(in, line); ++n) {
        std::istringstream s(line);
        std::string t, name, pid, rss, cpu, lost;
        ResourceRow r;
        try {
            if (!(std::getline(s, t, ',') && std::getline(s, name, ',') && std::getline(s, pid, ',') &&
                  std::getline(s, rss, ',') && std::getline(s, cpu, ',') && std::getline(s, lost)))
                throw std::invalid_argument("fields");
            r = {std::stod(t),
                 name,
                 static_cast<pid_t>(std::stol(pid)),
                 {std::stod(rss), std::stod(cpu)},
                 std::stoull(lost)};
        } catch (const std::exception&) {
            throw InputError(log::cat(path, ":", n, ": expected ", kResourceHeader, ", got '",
                                      quote_bytes(line, kQuotedBytes), "'"));
        }
        rows.push_back(std::move(r));
    }
    return rows;
}

}  // namespace dw::lab
