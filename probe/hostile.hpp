#pragma once
// Hostile samples on the lab's topics (issue 70, the hostile-wire suite; `dw-probe hostile`). Each
// is a real sample of the topic's type (probe/samples.hpp), serialized, then made malformed, so
// that what a process meets is a wire's failure rather than a test's invention:
// - encapsulation: an encapsulation id no CDR reader knows (it threw BadParamException inside
//   every reader, and the process aborted);
// - truncated: cut to at most half its length (the decoder runs out of bytes);
// - garbage: past the encapsulation header, about every fourth 8-byte word replaced with NaN,
//   ±inf, 1e300 or all ones (decodable or not, absurd values either way).
// Garbage goes only to sensor topics that command nothing: on a command or state topic a
// decodable sample is a forgery, which the lab's DDS Security keeps out (docs/SECURITY.md); the
// two undecodable kinds go to every topic. Published with each topic's own QoS, as the lab's
// writers would, so that every reader matches.
#include <array>
#include <cstdint>
#include <map>
#include <ostream>
#include <random>
#include <stop_token>
#include <string>
#include <vector>

#include "dds/config.hpp"

namespace dw::probe {

enum class Corruption { encapsulation, truncated, garbage };
inline constexpr std::array<const char*, 3> kCorruptionNames{"encapsulation", "truncated", "garbage"};

// `good` (a serialized sample, its 4-byte encapsulation header first) made malformed.
std::vector<std::uint8_t> corrupt(std::vector<std::uint8_t> good, Corruption c, std::mt19937_64& rng);

struct HostileOptions {
    std::vector<std::string> topics;  // suffixes; empty: every lab topic
    // PX4 clients' namespaces whose output topics (odometry, status, ack; v1.15's layout) get the
    // same corruptions; empty: none.
    std::vector<std::string> px4_namespaces;
    bool lab_topics = true;  // false: PX4's output topics only
    double rate_hz = 20;     // rounds per second, one sample per topic each
    double seconds = 0;      // 0: until stopped
    std::uint64_t seed = 1;
    std::stop_token stop;
};
// Samples sent, per topic suffix and corruption ("stand/wrench garbage").
using HostileCounts = std::map<std::string, std::uint64_t>;

HostileCounts run_hostile(const dds::DdsConfig& cfg, const HostileOptions& o, std::ostream& out);

}  // namespace dw::probe
