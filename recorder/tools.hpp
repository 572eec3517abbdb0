#pragma once
// What dw-recorder does with a recording on DDS: replay. (Reading recordings without DDS — info,
// export, the flight they hold — is recordings/recordings.hpp.)
#include <cstdint>
#include <functional>
#include <stop_token>
#include <string>
#include <vector>

#include "dds/participant.hpp"

namespace dw::recorder {

struct ReplayOptions {
    double speed = 1.0;               // x N
    std::vector<std::string> topics;  // suffixes; empty = all
    int wait_readers = 0;             // wait for this many readers per topic first
    // Replay command topics too (dds::Topic::command: setpoints, experiment commands). Off by
    // default: a replay beside a live lab must not move its vehicles.
    bool commands = false;
    std::function<void(double)> progress;
    std::stop_token stop;  // ends the replay (and the wait for readers)
};
struct ReplayStats {
    std::uint64_t sent = 0;
    std::uint64_t refused = 0;          // command samples holding NaN or inf: never published
    std::vector<std::string> left_out;  // recorded command topics not replayed (no --commands)
};
// Publishes the recorded samples back on DDS with their original timing.
ReplayStats replay(const std::string& path, dds::Participant& p, const ReplayOptions& o);

}  // namespace dw::recorder
