#pragma once
// How a process joins the lab's DDS domain: from defaults, a config file's `dds:` section and CLI
// flags (in that order of precedence, flags last).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/config.hpp"

// Declared only: CLI11 and Fast DDS's QoS headers cost seconds of compile time in every file that
// would include them through this one (dds/config.cpp and the callers include them).
namespace CLI {
class App;
}
namespace eprosima::fastdds::dds {
class DomainParticipantQos;
}

namespace dw::dds {

// local: everything on loopback (the default on one machine and in every test; nothing leaves the
// host). lab: the real network, multicast discovery or a discovery server.
enum class Profile { local, lab };
// default: UDP alone (why: dds/config.cpp); shm: shared memory only (one host); udp: UDP only.
enum class Transport { default_, shm, udp };
inline constexpr const char* kProfileNames[] = {"local", "lab"};             // Profile's values in order
inline constexpr const char* kTransportNames[] = {"default", "shm", "udp"};  // Transport's values in order

inline constexpr int kMaxDomainId = 232;  // RTPS port mapping: 7400 + 250 * domain must fit
inline constexpr Range kDomainRange{0, kMaxDomainId};
inline constexpr Range kReadersRange{0, 1000};  // "wait for this many readers per topic"
inline constexpr std::string_view kDefaultNamespace = "lab";
// How long a sensor writer holds its first sample for the lab's required readers (--await-readers).
inline constexpr double kDefaultAwaitTimeoutS = 5.0;
inline constexpr Range kAwaitTimeoutRange{0.1, 120.0, "s"};
// RTPS participant ids: the local profile's initial peers reach ids 0..kMaxParticipantId on a host.
inline constexpr int kMaxParticipantId = 31;
inline constexpr int kAutoParticipantId = -1;  // the lowest free one
inline constexpr Range kParticipantIdRange{0, kMaxParticipantId};

struct DdsConfig {
    int domain = 0;
    Profile profile = Profile::local;
    Transport transport = Transport::default_;
    std::vector<std::string> initial_peers;  // "ip" or "ip:port"; local adds 127.0.0.1
    std::string discovery_server;            // "ip:port" (lab profile); "" = multicast discovery
    std::vector<std::string> interfaces;     // lab profile: UDP interface whitelist (addresses)
    std::string ns{kDefaultNamespace};       // topics are rt/<ns>/...
    std::string security;                    // keystore folder (dds/security.hpp); "" = no DDS Security
    std::string identity;                    // the keystore identity; "" = the process's name
    bool insecure = false;                   // the lab profile without a keystore, said explicitly
    // Processes (their participant names: recorder, predictor, ...) whose readers every sensor
    // writer waits for before its first sample, so a recorder already running loses nothing of a
    // process that starts after it. Bounded by await_timeout_s; empty = publish at once.
    std::vector<std::string> await_readers;
    double await_timeout_s = kDefaultAwaitTimeoutS;
    // Per process, never from a shared file. A restarted process needs one its predecessor did not
    // have: over shared memory (the default until 2026-11-29, `shm` now) Fast DDS 2.9.1's peers
    // keep sending to the dead one's port, and a new participant on the same id heard nothing for
    // ~2 s (measured: dw_lab_tests ARecorderKilled...). Kept under UDP too, as a margin.
    int participant_id = kAutoParticipantId;
};

Profile parse_profile(std::string_view text);
Transport parse_transport(std::string_view text);
std::string to_string(Profile p);
std::string to_string(Transport t);

// Validates every field; throws dw::InputError naming the field (and `where`, e.g. a file).
void validate(const DdsConfig& config, std::string_view where = "");

// Raw CLI values; empty/absent = not given on the command line.
struct DdsCliOptions {
    std::optional<int> domain;
    std::optional<std::string> profile;
    std::optional<std::string> transport;
    std::vector<std::string> peers;
    std::optional<std::string> discovery_server;
    std::optional<std::string> ns;
    std::optional<std::string> security;
    std::optional<std::string> identity;
    bool insecure = false;
    std::vector<std::string> await_readers;
    std::optional<double> await_timeout_s;
    std::optional<int> participant_id;
};

void add_cli_options(CLI::App& app, DdsCliOptions& options);
// Merges defaults < config file `dds:` section < CLI flags, validated.
DdsConfig resolve(const DdsCliOptions& cli, const ConfigFile& file);

// The configuration as command-line flags, to hand to a child process.
std::vector<std::string> to_args(const DdsConfig& config);

// The Fast DDS participant QoS for a configuration (also used by the raw-DDS benchmark, so
// both sides of a comparison use the same transports).
eprosima::fastdds::dds::DomainParticipantQos participant_qos(const DdsConfig& config, const std::string& name);

}  // namespace dw::dds
