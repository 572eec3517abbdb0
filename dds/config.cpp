#include "dds/config.hpp"

#include <CLI/CLI.hpp>
#include <fastdds/dds/domain/qos/DomainParticipantQos.hpp>

#include <arpa/inet.h>

#include <fastdds/rtps/attributes/ServerAttributes.h>
#include <fastdds/rtps/transport/UDPv4TransportDescriptor.h>
#include <fastdds/rtps/transport/shared_mem/SharedMemTransportDescriptor.h>
#include <fastrtps/utils/IPLocator.h>

#include "core/cli.hpp"
#include "core/keys.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "dds/security.hpp"

namespace dw::dds {
namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;

namespace {
constexpr std::uint32_t kSocketBuffer = 4 * 1024 * 1024;             // large samples over UDP need it
constexpr std::uint32_t kInitialPeersRange = kMaxParticipantId + 1;  // participants per host reachable
// A participant's periodic announcement (and its lease: a peer silent this long is dropped).
// A participant that joins late (a restarted process) is often answered only at its peers' next
// periodic announcement (Fast DDS 2.9): a restarted recorder matched the stand's wrench writer after
// 0.36-0.46 s (2 of 7 runs) at a 1 s period here, and lost 1.3 s of it in CI (limit 1 s); within
// 0.25 s at a 0.2 s period (4 of 8 runs slow) and within 0.09 s at 0.25 s (6 runs), a busy loop
// beside them (tests/test_lab.cpp, LabRun.ARecorderKilledMid...). Four announcements a second to
// the 32 ports of a host is about a hundred small datagrams a second per participant on loopback.
constexpr std::uint32_t kAnnouncementPeriod_ns = 250'000'000;
constexpr std::int32_t kLease_s = 5;

constexpr const char* kProfileWhat = "DDS profile";
constexpr const char* kTransportWhat = "transport";

std::string prefix(std::string_view where) { return where.empty() ? std::string() : std::string(where) + ": "; }

bool is_ipv4(const std::string& text) {
    in_addr addr{};
    return inet_pton(AF_INET, text.c_str(), &addr) == 1;
}

// "ip" or "ip:port" -> (ip, port or 0). Throws InputError.
std::pair<std::string, std::uint32_t> split_address(const std::string& text, bool need_port, const std::string& field) {
    const auto colon = text.find(':');
    std::string ip = text.substr(0, colon);
    std::uint32_t port = 0;
    if (!is_ipv4(ip)) {
        throw InputError(log::cat(field, ": '", text, "' is not an IPv4 address"));
    }
    if (colon != std::string::npos) {
        const std::string p = text.substr(colon + 1);
        char* end = nullptr;
        const long v = std::strtol(p.c_str(), &end, 10);
        if (p.empty() || *end != '\0' || v <= 0 || v > 65535) {
            throw InputError(log::cat(field, ": '", text, "' has no valid port (1-65535)"));
        }
        port = static_cast<std::uint32_t>(v);
    } else if (need_port) {
        throw InputError(log::cat(field, ": '", text, "' needs a port, as in 127.0.0.1:11811"));
    }
    return {ip, port};
}
}  // namespace

Profile parse_profile(std::string_view text) { return parse_name<Profile>(kProfileNames, text, kProfileWhat); }
Transport parse_transport(std::string_view text) {
    return parse_name<Transport>(kTransportNames, text, kTransportWhat);
}
std::string to_string(Profile p) { return name_of(kProfileNames, p); }
std::string to_string(Transport t) { return name_of(kTransportNames, t); }

void validate(const DdsConfig& c, std::string_view where) {
    const std::string p = prefix(where);
    if (c.domain < 0 || c.domain > kMaxDomainId) {
        throw InputError(log::cat(p, "domain id ", c.domain, " is out of range (0-", kMaxDomainId, ")"));
    }
    try {
        for (const auto& peer : c.initial_peers) split_address(peer, false, "initial peer");
        if (!c.discovery_server.empty()) split_address(c.discovery_server, true, "discovery server");
        for (const auto& iface : c.interfaces) split_address(iface, false, "interface");
    } catch (const InputError& e) {
        throw InputError(p + e.what());
    }
    if (c.profile == Profile::local && !c.discovery_server.empty()) {
        throw InputError(p + "a discovery server needs the lab profile (--profile lab)");
    }
    if (c.profile == Profile::local && !c.interfaces.empty()) {
        throw InputError(p + "the local profile always uses loopback; interfaces need --profile lab");
    }
    if (c.transport == Transport::shm && !c.discovery_server.empty()) {
        throw InputError(p + "a discovery server cannot be reached over shared memory only");
    }
    if (c.transport == Transport::shm && !c.security.empty()) {
        throw InputError(p +
                         "DDS Security over shared memory sometimes never authenticates (Fast DDS 2.9.1); use "
                         "--transport udp or default");
    }
    if (c.ns.empty() || c.ns.find_first_of(" \t/") != std::string::npos) {
        throw InputError(log::cat(p, "namespace '", c.ns, "' must be one non-empty word without '/'"));
    }
    for (const auto& name : c.await_readers)
        if (name.empty() || name.find_first_of(" \t,/") != std::string::npos)
            throw InputError(log::cat(p, "await readers: '", name, "' is not a process name"));
    if (const auto problem = range_problem(c.await_timeout_s, kAwaitTimeoutRange); !problem.empty())
        throw InputError(log::cat(p, "await timeout: ", problem));
    if (c.participant_id != kAutoParticipantId) {
        if (const auto problem = range_problem(c.participant_id, kParticipantIdRange); !problem.empty())
            throw InputError(log::cat(p, "participant id: ", problem));
    }
}

namespace {
// Once the file and the flags are merged (a file may say `profile: lab` and the flags the keystore).
void require_security_choice(const DdsConfig& c) {
    if (c.profile == Profile::lab && c.security.empty() && !c.insecure)
        throw InputError(
            "the lab profile needs a keystore (--security DIR, made by dw-lab keys create) or an explicit --insecure");
}
}  // namespace

void add_cli_options(CLI::App& app, DdsCliOptions& o) {
    app.add_option("--domain", o.domain, "DDS domain id (0-232)")->type_name("ID")->check(cli::in(kDomainRange));
    app.add_option("--profile", o.profile, "local (loopback only, default) or lab (real network)")->type_name("NAME");
    app.add_option("--transport", o.transport, "default (UDP alone), shm (shared memory, one host) or udp")
        ->type_name("NAME");
    app.add_option("--peer", o.peers, "initial peer ip[:port] (repeatable)")->type_name("ADDR");
    app.add_option("--discovery-server", o.discovery_server, "discovery server ip:port (lab profile)")
        ->type_name("ADDR");
    app.add_option("--namespace", o.ns, "topic namespace: topics are rt/<ns>/... (default lab)")->type_name("NS");
    app.add_option("--security", o.security, "DDS Security keystore (dw-lab keys create); required by the lab profile")
        ->type_name("DIR");
    app.add_option("--identity", o.identity, "the keystore identity to join as (default: the process's name)")
        ->type_name("NAME");
    app.add_flag("--insecure", o.insecure,
                 "the lab profile without DDS Security (anyone on the network can command the vehicles)");
    app.add_option("--await-readers", o.await_readers,
                   "processes (e.g. recorder) whose readers each sensor topic waits for before its first sample")
        ->type_name("NAME")
        ->delimiter(',');
    app.add_option("--await-timeout", o.await_timeout_s, "how long a sensor topic waits for them, s (default 5)")
        ->type_name("S")
        ->check(cli::in(kAwaitTimeoutRange));
    app.add_option("--participant-id", o.participant_id,
                   "RTPS participant id (default: the lowest free; dw-lab gives a restarted process a fresh one)")
        ->type_name("N")
        ->check(cli::in(kParticipantIdRange));
}

namespace {

// The `dds:` section of a configuration file: each key once (core/keys.hpp).
constexpr const char* kFileSection = "dds";

void file_keys(KeyVisitor& k, DdsConfig& c) {
    k.integer("domain", c.domain, kDomainRange);
    k.enumeration("profile", c.profile, kProfileNames, kProfileWhat);
    k.enumeration("transport", c.transport, kTransportNames, kTransportWhat);
    k.texts("initial_peers", c.initial_peers);
    k.text("discovery_server", c.discovery_server);
    k.texts("interfaces", c.interfaces);
    k.text("namespace", c.ns);
    k.text("security", c.security);
    k.text("identity", c.identity);
    k.texts("await_readers", c.await_readers);
    k.number("await_timeout_s", c.await_timeout_s, kAwaitTimeoutRange);
}

}  // namespace

DdsConfig resolve(const DdsCliOptions& cli, const ConfigFile& file) {
    DdsConfig c;
    if (!file.empty()) {
        read_section(file.root(), file.path(), kFileSection, [&](KeyVisitor& k) { file_keys(k, c); });
        validate(c, file.path());
    }
    if (cli.domain) c.domain = *cli.domain;
    if (cli.profile) c.profile = parse_profile(*cli.profile);
    if (cli.transport) c.transport = parse_transport(*cli.transport);
    if (!cli.peers.empty()) c.initial_peers = cli.peers;
    if (cli.discovery_server) c.discovery_server = *cli.discovery_server;
    if (cli.ns) c.ns = *cli.ns;
    if (cli.security) c.security = *cli.security;
    if (cli.identity) c.identity = *cli.identity;
    if (cli.insecure) c.insecure = true, c.security.clear();
    if (!cli.await_readers.empty()) c.await_readers = cli.await_readers;
    if (cli.await_timeout_s) c.await_timeout_s = *cli.await_timeout_s;
    if (cli.participant_id) c.participant_id = *cli.participant_id;
    validate(c);
    require_security_choice(c);
    return c;
}

std::vector<std::string> to_args(const DdsConfig& c) {
    std::vector<std::string> a{"--domain",    std::to_string(c.domain), "--profile",   to_string(c.profile),
                               "--transport", to_string(c.transport),   "--namespace", c.ns};
    for (const auto& peer : c.initial_peers) a.insert(a.end(), {"--peer", peer});
    if (!c.discovery_server.empty()) a.insert(a.end(), {"--discovery-server", c.discovery_server});
    if (!c.security.empty()) a.insert(a.end(), {"--security", c.security});  // each child joins as its own identity
    if (c.insecure) a.emplace_back("--insecure");
    if (!c.await_readers.empty()) {
        a.insert(a.end(),
                 {"--await-readers", log::join(c.await_readers, ","), "--await-timeout", log::cat(c.await_timeout_s)});
    }
    return a;
}

fdds::DomainParticipantQos participant_qos(const DdsConfig& c, const std::string& name) {
    validate(c);
    fdds::DomainParticipantQos qos = fdds::PARTICIPANT_QOS_DEFAULT;
    qos.name(name);
    auto& transport = qos.transport();
    const bool want_udp = c.transport != Transport::shm;
    // The default is UDP alone. Fast DDS 2.9.1's shared memory, beside UDP: a pair of secure
    // participants sometimes never authenticates and samples drop in bursts under load
    // (docs/BENCHMARKS.md, DDS Security); a SIGKILLed peer's port is health-checked on the
    // sender's thread under its send lock (up to 1 s), stalling every writer of the sender — two
    // lab runs saw a crash of one process abort the experiment for another's silence. On loopback
    // it is no faster here (docs/BENCHMARKS.md, latency). `shm` still asks for it.
    const bool want_shm = c.transport == Transport::shm;
    transport.use_builtin_transports = false;
    if (want_udp) {
        auto udp = std::make_shared<eprosima::fastdds::rtps::UDPv4TransportDescriptor>();
        udp->sendBufferSize = kSocketBuffer;
        udp->receiveBufferSize = kSocketBuffer;
        udp->maxInitialPeersRange = kInitialPeersRange;
        if (c.profile == Profile::local) {
            udp->interfaceWhiteList = {"127.0.0.1"};
        } else {
            udp->interfaceWhiteList = c.interfaces;
        }
        transport.user_transports.push_back(udp);
    }
    if (want_shm) {
        auto shm = std::make_shared<eprosima::fastdds::rtps::SharedMemTransportDescriptor>();
        transport.user_transports.push_back(shm);
    }

    auto& builtin = qos.wire_protocol().builtin;
    qos.wire_protocol().participant_id = c.participant_id;
    std::vector<std::string> peers = c.initial_peers;
    if (c.profile == Profile::local && want_udp) peers.emplace_back("127.0.0.1");
    for (const auto& peer : peers) {
        auto [ip, port] = split_address(peer, false, "initial peer");
        frtps::Locator_t loc;
        frtps::IPLocator::setIPv4(loc, ip);
        loc.port = port;  // 0: every participant port of the domain on that host
        builtin.initialPeersList.push_back(loc);
    }
    if (!c.discovery_server.empty()) {
        auto [ip, port] = split_address(c.discovery_server, true, "discovery server");
        builtin.discovery_config.discoveryProtocol = frtps::DiscoveryProtocol_t::CLIENT;
        eprosima::fastdds::rtps::RemoteServerAttributes server;
        // The server's GUID prefix is mandatory in 2.9: the ROS 2 pattern for server id 0, as
        // `fast-discovery-server -i 0` uses.
        server.ReadguidPrefix("44.53.00.5f.45.50.52.4f.53.49.4d.41");
        frtps::Locator_t loc;
        frtps::IPLocator::setIPv4(loc, ip);
        loc.port = port;
        server.metatrafficUnicastLocatorList.push_back(loc);
        builtin.discovery_config.m_DiscoveryServers.push_back(server);
    }
    // Lets a peer that vanishes without saying goodbye be dropped within a few seconds.
    builtin.discovery_config.leaseDuration = eprosima::fastrtps::Duration_t(kLease_s, 0);
    builtin.discovery_config.leaseDuration_announcementperiod =
        eprosima::fastrtps::Duration_t(0, kAnnouncementPeriod_ns);
    if (!c.security.empty()) add_security(qos, c.security, c.identity.empty() ? name : c.identity);
    return qos;
}

}  // namespace dw::dds
