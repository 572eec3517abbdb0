// dw-bench-security: what DDS Security costs the lab, open and secure side by side in one run.
//   - Round trip: the planner's identity publishes vehicles/setpoint (encrypted under security),
//     an echo process as the mocap bridge answers on vehicles/state (signed); rounds alternate
//     open (domain D) and secure (domain D+1) so machine noise falls on both alike.
//   - Discovery: six lab processes started at once, each its role's endpoints, until every one
//     matched its peers (security_discovery.cpp), open and secure alternating.
// A keystore is made in a temporary folder (dw-lab keys' code).
//
//   dw-bench-security [--rounds 10] [--per-round 500] [--discovery-rounds 5]
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <mutex>
#include <numeric>
#include <thread>

#include "core/cli.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/process_cli.hpp"
#include "bench/security_discovery.hpp"
#include "security/keystore.hpp"

using namespace std::chrono_literals;
namespace topics = dw::dds::topics;

namespace {

dw::dds::DdsConfig with_security(dw::dds::DdsConfig c, const std::string& keys, const std::string& identity) {
    c.domain += 1;
    c.security = keys;
    c.identity = identity;
    return c;
}

// The echo side: answers every setpoint with a state, open and secure at once.
int run_pong(const dw::dds::DdsConfig& open, const std::string& keys) {
    struct Echo {
        dw::dds::Participant p;
        dw::dds::Writer<dw::msg::VehicleState> w;
        dw::dds::Reader<dw::msg::VehicleSetpoint> r;
        explicit Echo(const dw::dds::DdsConfig& c)
            : p(c, "mocap_bridge"),
              w(p, topics::vehicle_state),
              r(p, topics::vehicle_setpoint, [this](const auto& s, const auto&) {
                  dw::msg::VehicleState st;
                  st.vehicle_id(s.vehicle_id());
                  st.position_m(s.position_m());
                  w.write(st);
              }) {}
    };
    Echo a(open), b(with_security(open, keys, "mocap_bridge"));
    while (!dw::Shutdown::instance().wait_for(1s)) {}
    return 0;
}

// The pinging side. It sleeps on a condition variable until the reply (no busy loop: on 2 cores a
// spinning thread takes a core from the DDS threads doing the work being measured).
struct Pinger {
    dw::dds::Participant p;
    std::mutex m;
    std::condition_variable cv;
    std::uint64_t replies = 0;
    dw::dds::Reader<dw::msg::VehicleState> r;
    dw::dds::Writer<dw::msg::VehicleSetpoint> w;
    std::size_t lost = 0;
    explicit Pinger(const dw::dds::DdsConfig& c)
        : p(c, "planner"),
          r(p, topics::vehicle_state,
            [this](const auto&, const auto&) {
                {
                    std::lock_guard lock(m);
                    ++replies;
                }
                cv.notify_one();
            }),
          w(p, topics::vehicle_setpoint) {}
    // Round trips in µs; a ping unanswered in 100 ms (best effort) is counted lost.
    std::vector<double> run(std::size_t n) {
        std::vector<double> us;
        dw::msg::VehicleSetpoint s;
        s.vehicle_id("v1");
        for (std::size_t i = 0; i < n; ++i) {
            std::unique_lock lock(m);
            const auto before = replies;
            const auto t0 = std::chrono::steady_clock::now();
            s.position_m().x(static_cast<double>(i));
            w.write(s);
            if (!cv.wait_for(lock, 100ms, [&] { return replies != before; })) ++lost;
            else us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
        }
        return us;
    }
};

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size() - 1))];
}

void row(const char* name, const std::vector<double>& v, std::size_t lost) {
    const double mean = v.empty() ? NAN : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
    std::printf("| %-8s | %7zu | %5zu | %8.1f | %8.1f | %8.1f | %8.1f |\n", name, v.size(), lost, percentile(v, 50),
                percentile(v, 90), percentile(v, 99), mean);
}

int run(int argc, char** argv) {
    dw::Shutdown::install();
    dw::dds::ProcessCli cli("dw-bench-security: DDS Security's cost: round trip, open beside secure");
    CLI::App& app = cli.app();
    std::string pong_keys, member;
    int rounds = 10, discovery_rounds = 5;
    double t0_ms = 0, stagger_s = 0;
    std::size_t per_round = 500;
    app.add_option("--pong", pong_keys, "(internal) run the echo side with this keystore");
    app.add_option("--member", member, "(internal) one process of the discovery rounds, as this role");
    app.add_option("--t0-ms", t0_ms, "(internal) the discovery round's start, CLOCK_MONOTONIC ms")
        ->check(dw::cli::in({0, 1e15}));
    app.add_option("--stagger", stagger_s, "seconds between the discovery rounds' process starts")
        ->check(dw::cli::in({0, 10}));
    app.add_option("--discovery-rounds", discovery_rounds, "6-process discovery rounds, open and secure (0: none)")
        ->check(dw::cli::in({0, 100}));
    app.add_option("--rounds", rounds, "alternating open/secure rounds")->check(dw::cli::in({1, 1000}));
    app.add_option("--per-round", per_round, "round trips per round")->check(dw::cli::in({10, 1e6}));
    cli.parse(argc, argv);
    dw::dds::DdsConfig cfg = cli.dds();
    if (!pong_keys.empty()) return run_pong(cfg, pong_keys);
    if (!member.empty()) return dw::bench::run_discovery_member(cfg, member, t0_ms);
    if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "bsec" + std::to_string(::getpid());
    const std::string keys =
        (std::filesystem::temp_directory_path() / ("dw-bench-keys-" + std::to_string(::getpid()))).string();
    dw::security::create_keystore({keys, dw::security::role_identities(), 1});

    std::vector<std::string> args{dw::executable_dir() + "/dw-bench-security", "--pong", keys};
    for (const auto& a : dw::dds::to_args(cfg)) args.push_back(a);
    dw::Subprocess ponger({args, "", "", {}});
    Pinger open(cfg), secure(with_security(cfg, keys, "planner"));
    if (!open.w.wait_for_readers(1, 30s) || !secure.w.wait_for_readers(1, 30s))
        throw dw::RuntimeError("the echo process did not match");
    std::this_thread::sleep_for(1s);  // the secure side's keys follow the match
    open.run(200), secure.run(200);   // warm-up
    open.lost = secure.lost = 0;
    std::vector<double> open_all, secure_all;
    for (int r = 0; r < rounds; ++r) {
        auto a = open.run(per_round), b = secure.run(per_round);
        open_all.insert(open_all.end(), a.begin(), a.end());
        secure_all.insert(secure_all.end(), b.begin(), b.end());
        std::fprintf(stderr, "\rround %d/%d", r + 1, rounds);
    }
    std::fprintf(stderr, "\n");
    ponger.stop();

    std::printf("transport %s; vehicles/setpoint out, vehicles/state back (best effort); round trip in µs\n\n",
                dw::dds::to_string(cfg.transport).c_str());
    std::printf("| lab      | samples | lost  |   p50    |   p90    |   p99    |   mean   |\n");
    std::printf("|----------|---------|-------|----------|----------|----------|----------|\n");
    row("open", open_all, open.lost);
    row("secure", secure_all, secure.lost);
    std::printf("\nsecure / open at p50: %.2f x (target <= 1.3 x)\n\n",
                percentile(secure_all, 50) / percentile(open_all, 50));

    if (discovery_rounds > 0) dw::bench::run_discovery(cfg, keys, discovery_rounds, dw::to_millis(stagger_s));
    std::filesystem::remove_all(keys);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-security", [&] { return run(argc, argv); });
}
