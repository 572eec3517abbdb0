#pragma once
// The loopback session: a publisher and an echo process (dw-probe) on the local profile, every
// lab topic published, received, checked and shown. The lab's main job until the simulated lab
// exists.
#include <cstdint>
#include <stop_token>
#include <string>
#include <vector>

namespace dw::lab {

struct LoopbackOptions {
    std::string probe_path;             // dw-probe executable
    std::vector<std::string> dds_args;  // --domain/--transport/... passed to both children
    std::uint64_t count = 20;           // samples per topic
    double rate_hz = 20.0;
    double timeout_s = 60.0;
    bool quiet = false;        // children print only the summary
    std::string summary_path;  // echo's JSON summary ("" = a temporary file)
    std::stop_token stop;      // stops both children: exit 130
};

// Runs the session; returns the echo's exit status (0 = every topic arrived intact).
int run_loopback(const LoopbackOptions& o);

}  // namespace dw::lab
