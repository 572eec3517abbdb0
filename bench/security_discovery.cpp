// dw-bench-security --discovery: how long a 6-process lab takes to discover itself, open and
// secure. Each round starts six processes at once (stand agent, mocap bridge, planner,
// predictor, recorder, launcher), each a participant with the endpoints its role has in the topic
// registry (under security: its own identity and permissions). A process is discovered when every
// endpoint has matched every peer endpoint the registry implies among the six; the lab is
// discovered when the last process is. Times are from the round's start (CLOCK_MONOTONIC, shared
// by the processes of one machine), so process start-up and participant creation count.
#include "bench/security_discovery.hpp"

#include <unistd.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <memory>
#include <thread>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"

using namespace std::chrono_literals;

namespace dw::bench {
namespace {

constexpr std::array<dds::Role, 6> kLabRoles{dds::Role::stand_agent, dds::Role::mocap_bridge, dds::Role::planner,
                                             dds::Role::predictor,   dds::Role::recorder,     dds::Role::launcher};
constexpr auto kMatchTimeout = 60s;

dds::Roles lab_roles() {
    dds::Roles all = 0;
    for (auto r : kLabRoles) all |= static_cast<dds::Roles>(r);
    return all;
}
int members_in(dds::Roles set) { return std::popcount(set & lab_roles()); }

double now_ms() {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

// One role's endpoints and how many peers each should match.
struct Expected {
    std::string what;  // "writer stand/wrench"
    std::function<int()> matched;
    int target = 0;
};
struct Endpoints {
    std::vector<std::unique_ptr<void, void (*)(void*)>> held;
    std::vector<Expected> expected;
    bool all_matched() const {
        return std::all_of(expected.begin(), expected.end(), [](const Expected& e) { return e.matched() >= e.target; });
    }
    std::string missing() const {
        std::string out;
        for (const auto& e : expected)
            if (e.matched() < e.target) out += log::cat(" ", e.what, " ", e.matched(), "/", e.target);
        return out;
    }
};

template <class T>
void hold(Endpoints& e, T* endpoint, std::string what, int target) {
    e.held.emplace_back(endpoint, [](void* p) { delete static_cast<T*>(p); });
    e.expected.push_back({std::move(what), [endpoint] { return endpoint->matched(); }, target});
}

Endpoints endpoints_of(dds::Participant& p, dds::Role role) {
    Endpoints e;
    dds::topics::for_each([&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        const std::string topic(spec.suffix);
        if (dds::has(spec.producers, role))
            hold(e, new dds::Writer<T>(p, spec), "writer " + topic, members_in(spec.consumers));
        if (dds::has(spec.consumers, role))
            hold(e, new dds::Reader<T>(p, spec, [](const T&, const dds::SampleMeta&) {}), "reader " + topic,
                 members_in(spec.producers));
    });
    return e;
}

}  // namespace

int run_discovery_member(const dds::DdsConfig& c, const std::string& role_name, double t0_ms) {
    const auto role = dds::role_named(role_name);
    if (!role) throw InputError("--member: unknown role '" + role_name + "'");
    dds::Participant p(c, role_name);
    const Endpoints e = endpoints_of(p, *role);
    const double deadline = now_ms() + std::chrono::duration<double, std::milli>(kMatchTimeout).count();
    while (!e.all_matched() && now_ms() < deadline) std::this_thread::sleep_for(1ms);
    std::printf("%s %.1f%s\n", e.all_matched() ? "matched" : "timeout", now_ms() - t0_ms, e.missing().c_str());
    std::fflush(stdout);
    while (!Shutdown::instance().wait_for(1s)) {}  // others may still be matching this one
    return 0;
}

namespace {

// The lab's discovery time in ms (the slowest process), or a negative value when a process did
// not match everything within the timeout.
double one_round(const std::vector<std::string>& base_args, const std::string& dir, std::chrono::milliseconds stagger) {
    const double t0 = now_ms();
    std::vector<std::unique_ptr<Subprocess>> procs;
    std::vector<std::string> outs;
    for (auto r : kLabRoles) {
        std::vector<std::string> args = base_args;
        const std::string name(dds::role_name(r));
        args.insert(args.end(), {"--member", name, "--t0-ms", log::cat(t0)});
        outs.push_back(dir + "/" + name + ".out");
        procs.push_back(std::make_unique<Subprocess>(SpawnOptions{args, outs.back(), dir + "/" + name + ".err", {}}));
        std::this_thread::sleep_for(stagger);
    }
    double slowest = 0;
    for (const auto& out : outs) {
        std::string text;
        const double deadline = now_ms() + 90'000;
        while ((text = std::filesystem::exists(out) ? read_file(out) : "").find('\n') == std::string::npos &&
               now_ms() < deadline)
            std::this_thread::sleep_for(10ms);
        double ms = -1;
        if (text.rfind("matched ", 0) == 0) ms = std::stod(text.substr(8));
        else std::fprintf(stderr, "\n%s: %s", out.c_str(), text.empty() ? "no answer\n" : text.c_str());
        slowest = ms < 0 || slowest < 0 ? -1 : std::max(slowest, ms);
    }
    for (auto& p : procs) p->stop();
    return slowest;
}

}  // namespace

void run_discovery(const dds::DdsConfig& cfg, const std::string& keys, int rounds, std::chrono::milliseconds stagger) {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("dw-bench-disc-" + std::to_string(::getpid()))).string();
    std::filesystem::create_directories(dir);
    std::vector<double> open, secure;
    for (int r = 0; r < rounds; ++r) {
        for (bool sec : {false, true}) {
            dds::DdsConfig c = cfg;
            c.ns = log::cat(cfg.ns, "d", r, sec ? "s" : "o");
            std::vector<std::string> args{executable_dir() + "/dw-bench-security"};
            for (const auto& a : dds::to_args(c)) args.push_back(a);
            if (sec) args.insert(args.end(), {"--security", keys});
            (sec ? secure : open).push_back(one_round(args, dir, stagger));
            std::fprintf(stderr, "\rdiscovery round %d/%d", r + 1, rounds);
        }
    }
    std::fprintf(stderr, "\n");
    std::filesystem::remove_all(dir);
    auto show = [](const char* name, std::vector<double> v) {
        const auto failed = std::count_if(v.begin(), v.end(), [](double x) { return x < 0; });
        v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return x < 0; }), v.end());
        std::sort(v.begin(), v.end());
        const auto at = [&](std::size_t i) { return v.empty() ? NAN : v[i]; };
        std::printf("| %-8s | %6zu | %6ld | %8.0f | %8.0f | %8.0f |\n", name, v.size(), static_cast<long>(failed),
                    at(0), at(v.size() / 2), at(v.empty() ? 0 : v.size() - 1));
    };
    std::printf(
        "6-process lab (stand agent, mocap bridge, planner, predictor, recorder, launcher), every endpoint its role "
        "has,\n"
        "started %lld ms apart; time from the first start until the last process matched every peer endpoint, in "
        "ms\n\n",
        static_cast<long long>(stagger.count()));
    std::printf("| lab      | rounds | failed |   min    |  median  |   max    |\n");
    std::printf("|----------|--------|--------|----------|----------|----------|\n");
    show("open", open);
    show("secure", secure);
    std::printf("\n(target: the whole lab discovered within 3000 ms)\n\n");
}

}  // namespace dw::bench
