#include "lab/loopback.hpp"

#include <unistd.h>

#include <chrono>
#include <cstdio>

#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"

namespace dw::lab {

int run_loopback(const LoopbackOptions& o) {
    const std::string summary =
        o.summary_path.empty() ? "/tmp/dw-loopback-" + std::to_string(::getpid()) + ".json" : o.summary_path;
    std::vector<std::string> echo_args{o.probe_path,
                                       "echo",
                                       "all",
                                       "--name",
                                       "loopback-echo",
                                       "--expect",
                                       std::to_string(o.count),
                                       "--timeout",
                                       std::to_string(o.timeout_s),
                                       "--summary",
                                       summary};
    std::vector<std::string> pub_args{o.probe_path,
                                      "pub",
                                      "all",
                                      "--name",
                                      "loopback-pub",
                                      "--count",
                                      std::to_string(o.count),
                                      "--rate",
                                      std::to_string(o.rate_hz),
                                      "--wait-readers",
                                      "1",
                                      "--wait-timeout",
                                      std::to_string(o.timeout_s),
                                      "--linger",
                                      "-1",
                                      "--quiet"};
    if (o.quiet) echo_args.emplace_back("--quiet");
    echo_args.insert(echo_args.end(), o.dds_args.begin(), o.dds_args.end());
    pub_args.insert(pub_args.end(), o.dds_args.begin(), o.dds_args.end());

    log::info("loopback session: 2 processes, ", o.count, " samples on each of the lab's topics");
    Subprocess echo({echo_args, "", "", {}});
    Subprocess pub({pub_args, "", "", {}});
    log::info("started echo (pid ", echo.pid(), ") and publisher (pid ", pub.pid(), ")");

    std::optional<int> status;
    while (!(status = echo.wait_for(std::chrono::milliseconds(100)))) {
        if (o.stop.stop_requested()) {
            echo.stop();
            pub.stop();
            log::warn("interrupted");
            return 130;
        }
        if (auto p = pub.poll(); p && *p != 0) {
            log::error("the publisher failed (exit ", *p, ")");
            echo.stop();
            return 1;
        }
    }
    pub.stop();
    if (*status == 0) {
        log::info("every topic type was published, received intact and shown; summary in ", summary);
    } else {
        log::error("the loopback session failed (echo exit ", *status, "); summary in ", summary);
    }
    return *status;
}

}  // namespace dw::lab
