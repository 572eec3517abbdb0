// dw-lab: lab files (located errors), the progress bar, `dw-lab run` on loopback (a process
// printed for another host, a failing process restarted), across two network namespaces (one
// per host), and `dw-lab demo --quick` end to end.
#include <gtest/gtest.h>
#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <mutex>
#include <span>
#include <sstream>
#include <stop_token>
#include <thread>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/subprocess.hpp"
#include "lab/labfile.hpp"
#include "lab/launcher.hpp"
#include "lab/soak.hpp"
#include "dds/security.hpp"
#include "security/keystore.hpp"
#include "mcap/mcap.hpp"
#include "recordings/recordings.hpp"
#include "dds/endpoint.hpp"
#include "dds/px4.hpp"
#include "swarm_planner/px4_config.hpp"
#include "px4_sim/wire.hpp"
#include "dds/raw.hpp"
#include "swarm_planner/plan.hpp"
#include "support.hpp"

using namespace std::chrono_literals;
using dw::test::bin;

namespace {

std::string error_of(const std::string& yaml) {
    try {
        dw::lab::parse_lab(yaml, "lab.yaml");
    } catch (const dw::InputError& e) {
        return e.what();
    }
    return "";
}

const char* kShort = R"(format: downwash-lab/1
vars: {legs: "2"}
hosts:
  local: {}
  elsewhere: {}
  %B%
processes:
  - name: stand_agent
    run: [dw-stand-agent, run, --sim]
  - name: mocap_bridge
    run: [dw-mocap-bridge, --sim, --sim-vehicles, v1]
  - name: recorder
    run: [dw-recorder, record, --out, "{run_dir}/exp.mcap", --quiet, --no-fsync]
  - name: predictor
    host: elsewhere
    run: [dw-predictor, run, --model, physics.yaml]
  - name: flaky
    run: [dw-predictor, run, --model, "{run_dir}/no-such-model.json"]
    restart: on-failure
  - name: planner
    host: %PLANNER_HOST%
    run: [dw-planner, run, --formation, single, --legs, "{legs}", --altitudes, "0.5", --speed, "1.0"]
    experiment: true
)";

std::string lab_text(const std::string& b_host, const std::string& planner_host) {
    std::string s = kShort;
    s.replace(s.find("%B%"), 3, b_host);
    s.replace(s.find("%PLANNER_HOST%"), 14, planner_host);
    return s;
}

// The lowest header.seq recorded per topic (suffix after the namespace).
std::map<std::string, std::uint64_t> first_recorded_seq(const std::string& file) {
    std::map<std::uint16_t, std::string> topics;
    std::map<std::string, std::uint64_t> first;
    const auto r = dw::mcap::read_file(
        file,
        {.on_channel = [&](const dw::mcap::Channel& c) { topics[c.id] = c.topic.substr(c.topic.find('/', 3) + 1); },
         .on_message =
             [&](const dw::mcap::Message& m) {
                 auto [it, fresh] = first.try_emplace(topics[m.channel_id], m.sequence);
                 if (!fresh) it->second = std::min<std::uint64_t>(it->second, m.sequence);
             }});
    EXPECT_FALSE(r.error) << *r.error;
    return first;
}

}  // namespace

TEST(LabFile, ReadsTheSimulatedLabAndNamesWhereItIsWrong) {
    const auto lab = dw::lab::load_lab(std::string(DW_SOURCE_DIR) + "/config/lab.sim.yaml");
    ASSERT_EQ(lab.processes.size(), 5u);
    EXPECT_TRUE(lab.processes.back().experiment);
    EXPECT_EQ(dw::lab::expand(lab.processes.back(), lab.vars)[3], "leader_follower3");
    EXPECT_NE(error_of("format: downwash-lab/2\nprocesses: []\n").find("lab.yaml:1:9: format"), std::string::npos);
    EXPECT_NE(error_of("format: downwash-lab/1\nprocesses:\n  - name: a\n    run: [dw-probe]\n    restart: sometimes\n")
                  .find("lab.yaml:5:14: processes[0].restart"),
              std::string::npos);
    EXPECT_NE(
        error_of("format: downwash-lab/1\nprocesses:\n  - name: a\n    run: [rm, -rf]\n").find("not a lab executable"),
        std::string::npos);
    EXPECT_NE(error_of("format: downwash-lab/1\nprocesses:\n  - name: a\n    host: mars\n    run: [dw-probe]\n")
                  .find("'mars' is not under hosts"),
              std::string::npos);
    // Issue 70: two recorders writing one file.
    EXPECT_NE(error_of("format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-recorder, record, --out, r.mcap]}\n"
                       "  - {name: b, run: [dw-recorder, record, --out, r.mcap]}\n")
                  .find("processes[1].run: --out 'r.mcap' is also a's: two writers, one file"),
              std::string::npos)
        << error_of(
               "format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-recorder, record, --out, r.mcap]}\n"
               "  - {name: b, run: [dw-recorder, record, --out, r.mcap]}\n");
    EXPECT_NE(
        error_of("format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-probe]}\n  - {name: a, run: [dw-probe]}\n")
            .find("used twice"),
        std::string::npos);
    EXPECT_NE(
        error_of("format: downwash-lab/1\ncolour: red\nprocesses: []\n").find("lab.yaml:2:1: colour: unknown key"),
        std::string::npos);
    const auto lab2 =
        dw::lab::parse_lab("format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-probe, \"{what}\"]}\n", "x");
    EXPECT_THROW(dw::lab::expand(lab2.processes[0], {}), dw::InputError);
}

TEST(LabFile, ProgressBar) {
    EXPECT_EQ(dw::lab::progress_bar(7, 20, 0.35, 65, 20), "[#######.............] 7/20 legs  35 %  ETA 1:05");
    EXPECT_EQ(dw::lab::progress_bar(0, 4, 0, -1, 4), "[....] 0/4 legs  0 %");
}

TEST(LabRun, FliesALabFileRestartsAFailingProcessAndPrintsOtherHostsCommands) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << lab_text("", "local");
    const auto r =
        dw::test::run({bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"), "--domain",
                       std::to_string(dw::test::test_domain()), "--namespace", "labrun" + std::to_string(::getpid())},
                      dir, 300000ms);
    // Run 30 saw the experiment ABORTED here once (not reproduced): the planner's log says why.
    const auto planner_log = dir.file("run/logs/planner.log");
    ASSERT_EQ(r.status, 0) << r.err << "\nplanner.log:\n"
                           << (std::filesystem::exists(planner_log) ? dw::read_file(planner_log) : "(none)");
    EXPECT_NE(r.out.find("DONE: 2 of 2 legs"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("started elsewhere: elsewhere: "), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("dw-predictor run --model physics.yaml --domain"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("restarting flaky (3 of 3)"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("experiment     DONE"), std::string::npos) << r.err;  // the status block
    EXPECT_NE(r.err.find("stand_agent    RUNNING"), std::string::npos) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir.file("run/exp.mcap")));
    EXPECT_NE(dw::read_file(dir.file("run/logs/planner.log")).find("DONE"), std::string::npos);
    // Issue 19: the stand agent and the bridge start before the recorder, yet their first samples
    // are recorded (the launcher made them await the recorder's readers).
    EXPECT_NE(r.out.find("--await-readers recorder"), std::string::npos) << r.out;
    const auto first = first_recorded_seq(dir.file("run/exp.mcap"));
    for (const char* topic : {"stand/wrench", "stand/cells", "mocap/frame", "vehicles/state", "vehicles/setpoint"}) {
        ASSERT_TRUE(first.count(topic)) << topic;
        EXPECT_EQ(first.at(topic), 0u) << topic << ": the first samples were not recorded";
    }
}

namespace {
// The two-leg lab on this host (lab.yaml, its physics) and a keystore made from it (keys/).
void write_secure_lab(const dw::test::TempDir& dir) {
    std::string lab = lab_text("", "local");
    const auto flaky = lab.find("  - name: flaky");
    lab.erase(flaky, lab.find("  - name: planner") - flaky);
    lab.replace(lab.find("    host: elsewhere\n"), std::string("    host: elsewhere\n").size(), "");
    lab.replace(lab.find("physics.yaml]"), std::string("physics.yaml").size(),
                dir.file("physics.yaml"));  // here, not elsewhere
    std::ofstream(dir.file("lab.yaml")) << lab;
    std::ofstream(dir.file("physics.yaml")) << "format: downwash-physics/1\n";  // the predictor's model: the physics
    const auto keys = dw::test::run(
        {bin("dw-lab"), "keys", "create", "--keystore", dir.file("keys"), "--lab", dir.file("lab.yaml")}, dir);
    ASSERT_EQ(keys.status, 0) << keys.err;
    EXPECT_NE(keys.out.find("created identity planner"), std::string::npos) << keys.out;
}
}  // namespace

// Issue 18: the simulated lab with DDS Security, every process its own identity from a keystore
// made from the lab file; the recording is complete and says who recorded it.
TEST(LabRun, FliesTheLabWithDdsSecurityEveryProcessItsOwnIdentity) {
    dw::test::TempDir dir;
    ASSERT_NO_FATAL_FAILURE(write_secure_lab(dir));
    const auto r = dw::test::run({bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"),
                                  "--security", dir.file("keys"), "--domain", std::to_string(dw::test::test_domain()),
                                  "--namespace", "labsec" + std::to_string(::getpid())},
                                 dir, 300000ms);
    ASSERT_EQ(r.status, 0) << r.err << "\nplanner log:\n" << dw::read_file(dir.file("run/logs/planner.log"));
    EXPECT_NE(r.out.find("DONE: 2 of 2 legs"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("@local    auth "), std::string::npos)
        << "the status line says a process authenticated as its own identity\n"
        << r.err;
    EXPECT_EQ(r.err.find(" AS "), std::string::npos) << "no process spoke as another identity\n" << r.err;
    const auto info = dw::test::run({bin("dw-recorder"), "info", dir.file("run/exp.mcap")}, dir);
    ASSERT_EQ(info.status, 0) << info.err;
    for (const char* topic :
         {"stand/wrench", "mocap/frame", "vehicles/setpoint", "experiment/command", "predictor/wrench"}) {
        const auto at = info.out.find(std::string("/") + topic + " ");
        ASSERT_NE(at, std::string::npos) << topic << "\n" << info.out;
        EXPECT_EQ(info.out.find("lost 0", at), info.out.find("lost ", at)) << topic << ": no sample lost\n" << info.out;
    }
    EXPECT_NE(info.out.find("dds_security=identity recorder"), std::string::npos) << info.out;
    for (const char* log : {"planner", "stand_agent", "recorder", "predictor", "mocap_bridge"})
        EXPECT_EQ(dw::read_file(dir.file(std::string("run/logs/") + log + ".log")).find("SECURITY"), std::string::npos)
            << log;
}

namespace {
// A UDP port free on loopback now (the kernel's choice).
std::uint16_t free_udp_port() {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    socklen_t len = sizeof a;
    const bool ok = fd >= 0 && ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
                    ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0;
    if (fd >= 0) ::close(fd);
    return ok ? ntohs(a.sin_port) : 0;
}
}  // namespace

namespace {
// f_d's samples split by how far, horizontally, the nearest vehicle above the sufferer is: within
// `near_m`, and beyond `far_m` (or none above).
struct Moments {
    std::size_t n = 0;
    double sum = 0, sq = 0;
    void add(double x) { ++n, sum += x, sq += x * x; }
    double mean() const { return sum / static_cast<double>(n); }
    double var() const { return sq / static_cast<double>(n) - mean() * mean(); }
};
std::pair<Moments, Moments> f_d_near_and_far(const dw::flight::Flight& f, double near_m, double far_m) {
    std::vector<std::vector<const dw::flight::PoseSample*>> by(f.bodies.size());
    for (const auto& p : f.poses) by[p.body].push_back(&p);
    const auto sufferer =
        static_cast<std::size_t>(std::find(f.bodies.begin(), f.bodies.end(), f.meta.sufferer) - f.bodies.begin());
    auto at = [&](std::size_t b, double t) {
        const auto& v = by[b];
        const auto it = std::lower_bound(v.begin(), v.end(), t, [](const auto* p, double x) { return p->t < x; });
        return it == v.end() ? v.back() : *it;
    };
    Moments near, far;
    for (const auto& w : f.wrench) {
        const auto* s = at(sufferer, w.t);
        double nearest = std::numeric_limits<double>::infinity();
        for (std::size_t b = 0; b < by.size(); ++b) {
            if (b == sufferer || by[b].empty()) continue;
            const auto* p = at(b, w.t);
            if (p->p[2] < s->p[2]) nearest = std::min(nearest, std::hypot(p->p[0] - s->p[0], p->p[1] - s->p[1]));
        }
        if (nearest < near_m) near.add(w.w[2]);
        if (nearest > far_m) far.add(w.w[2]);
    }
    return {near, far};
}

// `dw-lab run` of the shipped PX4 lab file (config/lab.px4sim.yaml) with `legs` legs, the example
// physics, the simulated PX4s' settings file and their emulated Motive on `natnet_port`.
std::vector<std::string> px4_lab_argv(const dw::test::TempDir& dir, int legs, std::uint16_t natnet_port) {
    const std::string config = std::string(DW_SOURCE_DIR) + "/config/";
    return {bin("dw-lab"), "run",
            "--lab",       config + "lab.px4sim.yaml",
            "--run-dir",   dir.file("run"),
            "--var",       "legs=" + std::to_string(legs),
            "--var",       "physics=" + config + "physics.example.yaml",
            "--var",       "model=" + config + "physics.example.yaml",
            "--var",       "natnet_port=" + std::to_string(natnet_port),
            "--var",       "px4=" + config + "px4.sim.yaml"};
}
}  // namespace

// Issue 20: the shipped PX4 lab file flown end to end — the planner drives simulated PX4s over
// PX4's topics, the real NatNet client reads their emulated motion capture, the stand feels them.
TEST(LabRun, FliesThePx4LabFileWithSimulatedPx4sAndTheirMotionCapture) {
    dw::test::TempDir dir;
    const std::uint16_t port = free_udp_port();
    ASSERT_NE(port, 0);
    auto argv = px4_lab_argv(dir, 2, port);
    argv.insert(argv.end(), {"--domain", std::to_string(dw::test::test_domain()), "--namespace",
                             "labpx4" + std::to_string(::getpid())});
    const auto r = dw::test::run(argv, dir, 300000ms);
    ASSERT_EQ(r.status, 0) << r.err << "\nplanner log:\n" << dw::read_file(dir.file("run/logs/planner.log"));
    EXPECT_NE(r.out.find("DONE: 2 of 2 legs"), std::string::npos) << r.out;
    const std::string planner = dw::read_file(dir.file("run/logs/planner.log"));
    const std::string px4 = dw::read_file(dir.file("run/logs/px4_sim.log"));
    // Issue 42: the bridge feeds the estimators (odometry: bridge) from the start, so they are
    // ready before the planner arms: it never has to ask before PX4's pre-flight checks pass.
    EXPECT_NE(planner.find("odometry by bridge"), std::string::npos) << planner;
    EXPECT_EQ(planner.find("pre-flight checks still fail"), std::string::npos) << planner;
    for (const char* v : {"v1", "v2"}) {
        EXPECT_NE(planner.find(std::string(v) + ": PX4 system"), std::string::npos) << planner;
        EXPECT_NE(px4.find(std::string(v) + ": armed, 0 commands ignored (another system), 0 payloads undecodable"),
                  std::string::npos)
            << px4;
    }
    const auto info = dw::test::run({bin("dw-recorder"), "info", dir.file("run/recording.mcap")}, dir);
    ASSERT_EQ(info.status, 0) << info.err;
    for (const char* topic : {"stand/wrench", "mocap/frame", "vehicles/state", "predictor/wrench"}) {
        const auto at = info.out.find(std::string("/") + topic + " ");
        ASSERT_NE(at, std::string::npos) << topic << "\n" << info.out;
        const std::string line = info.out.substr(at, info.out.find('\n', at) - at);
        EXPECT_EQ(line.find("recorded 0,"), std::string::npos) << line << ": nothing recorded";
        EXPECT_NE(line.find("lost 0,"), std::string::npos) << line << ": samples lost";
    }
    // The stand felt the PX4s: with a vehicle above it within 0.8 m horizontally, f_d is higher
    // than with every vehicle beyond 1.2 m, by more than five standard errors. (This checked the
    // strongest sample once: the stand's untared samples, the hover thrust, held it whatever the
    // vehicles did, and with them left out one garbage sample did. Measured: +0.068 N against 0.000,
    // 16 standard errors.)
    const auto flight = dw::recordings::read_flight_or_recording(dir.file("run/recording.mcap"));
    const auto [near, far] = f_d_near_and_far(flight, 0.8, 1.2);
    ASSERT_GT(near.n, 30u) << "the vehicles never flew within 0.8 m of the stand";
    ASSERT_GT(far.n, 30u);
    const double se = std::sqrt(near.var() / near.n + far.var() / far.n);
    std::printf("f_d near %.4f N (%zu samples), far %.4f N (%zu): %.1f standard errors\n", near.mean(), near.n,
                far.mean(), far.n, (near.mean() - far.mean()) / se);
    EXPECT_GT(near.mean() - far.mean(), 5 * se) << "the stand never felt the vehicles";
}

namespace {
// Issue 70, the hostile-wire suite: `lab_argv` (dw-lab run ...) flown while `dw-probe hostile
// <probe_args>` publishes malformed samples, both with the DDS options `dds`; the probe is stopped
// once the lab ends. Checks what every such run must show: the probe stops cleanly, the lab ends
// DONE (`done_line` on its stdout) or ABORTED with a reason, and each of `survivors` stops with
// status 0.
struct HostileRun {
    bool ended = false, done = false;
    std::string out, err, probe_out;
};
HostileRun fly_under_hostile_probe(const dw::test::TempDir& dir, std::vector<std::string> lab_argv,
                                   const std::vector<std::string>& probe_args, const std::vector<std::string>& dds,
                                   std::chrono::milliseconds timeout, const std::string& done_line,
                                   const std::vector<const char*>& survivors) {
    lab_argv.insert(lab_argv.end(), dds.begin(), dds.end());
    dw::Subprocess lab({lab_argv, dir.file("lab.out"), dir.file("lab.err"), {}});
    std::vector<std::string> probe_argv{bin("dw-probe")};
    probe_argv.insert(probe_argv.end(), dds.begin(), dds.end());
    probe_argv.push_back("hostile");
    probe_argv.insert(probe_argv.end(), probe_args.begin(), probe_args.end());
    dw::Subprocess hostile({probe_argv, dir.file("hostile.out"), dir.file("hostile.err"), {}});
    const auto status = lab.wait_for(timeout);
    hostile.signal(SIGINT);
    EXPECT_EQ(hostile.wait_for(20000ms), std::optional<int>(0)) << dw::read_file(dir.file("hostile.err"));
    HostileRun r;
    r.ended = status.has_value();
    if (!r.ended) return r;
    r.out = dw::read_file(dir.file("lab.out"));
    r.err = dw::read_file(dir.file("lab.err"));
    r.probe_out = dw::read_file(dir.file("hostile.out"));
    r.done = r.out.find(done_line) != std::string::npos;
    EXPECT_TRUE(r.done || r.err.find("ABORTED") != std::string::npos) << r.out << r.err;
    for (const char* p : survivors)
        EXPECT_NE(r.err.find(std::string("stopped ") + p + " (status 0)"), std::string::npos)
            << p << " did not survive:\n"
            << r.err;
    return r;
}
}  // namespace

// Issue 70, the hostile-wire suite's full-size twin (--full): the PX4 lab file flies while `dw-probe
// hostile` publishes malformed samples on every lab topic and on each PX4's output topics (an
// unknown encapsulation, cut short; PX4's odometry also with NaN, ±inf and 1e300 words). Every
// process survives, the experiment ends DONE or ABORTED with a reason, and every trajectory setpoint
// read on the vehicles' own topics (fmu/in/trajectory_setpoint, where PX4 reads it) is finite and,
// through each vehicle's frame, inside the room.
TEST(HostileWireFull, ThePx4LabUnderMalformedSamplesOnItsAndPx4sTopicsSendsNoAbsurdSetpoint) {
    dw::test::TempDir dir;
    const std::string px4_file = std::string(DW_SOURCE_DIR) + "/config/px4.sim.yaml";
    const std::uint16_t port = free_udp_port();
    ASSERT_NE(port, 0);
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "hostilepx4" + std::to_string(::getpid());
    const auto px4 = dw::planner::load_px4_options(px4_file, {"v1", "v2"});
    dw::dds::RawParticipant watcher(cfg, "watcher");
    std::mutex m;
    std::vector<std::string> absurd;
    std::size_t checked = 0;
    const dw::planner::Geofence room;
    const auto& def = dw::px4sim::msg_def(dw::px4sim::Msg::trajectory_setpoint, dw::dds::Px4Version::v1_15);
    for (const auto& v : px4.vehicles)
        watcher.subscribe(dw::dds::px4_topic(v.ns, "in", "trajectory_setpoint"),
                          "px4_msgs::msg::dds_::TrajectorySetpoint_", [&, v](std::span<const std::uint8_t> b) {
                              const auto t = dw::px4sim::decode(def, b);
                              const auto at = [&](const char* f) {
                                  const auto& x = t.at(f);
                                  return dw::physics::Vec3(x[0], x[1], x[2]);
                              };
                              const auto lab = dw::planner::local_frame(v).lab_point(at("position"));
                              std::lock_guard lock(m);
                              ++checked;
                              if (!at("velocity").allFinite() || !at("acceleration").allFinite() ||
                                  !room.contains(lab, dw::planner::Geofence::kTolerance_m))
                                  absurd.push_back(v.name + " at " + std::to_string(lab.x()) + "," +
                                                   std::to_string(lab.y()) + "," + std::to_string(lab.z()));
                          });
    const std::vector<std::string> dds{"--domain", std::to_string(cfg.domain), "--namespace", cfg.ns};

    const auto run = fly_under_hostile_probe(dir, px4_lab_argv(dir, 4, port), {"--rate", "50", "--px4", "v1,v2"}, dds,
                                             600000ms, "DONE: 4 of 4 legs",
                                             {"stand_agent", "px4_sim", "mocap_bridge", "recorder", "predictor"});
    ASSERT_TRUE(run.ended) << "dw-lab did not end";
    EXPECT_NE(run.probe_out.find("fmu/out/vehicle_odometry garbage"), std::string::npos) << run.probe_out;
    std::lock_guard lock(m);
    EXPECT_GT(checked, 100u);
    EXPECT_TRUE(absurd.empty()) << absurd.size() << " absurd setpoints, the first " << absurd.front() << "\n"
                                << run.err;
    std::printf("%s%zu PX4 setpoints checked; %s\n", run.out.c_str(), checked, run.done ? "DONE" : "ABORTED");
}

TEST(LabRun, TheLabProfileWantsAKeystoreOrAnExplicitInsecure) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << lab_text("", "local");
    const auto r = dw::test::run(
        {bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"), "--profile", "lab"}, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(dw::test::lines(r.err).size(), 1u) << r.err;
    EXPECT_NE(r.err.find("--insecure"), std::string::npos) << r.err;
    EXPECT_FALSE(std::filesystem::exists(dir.file("run"))) << "refused before anything started";
    const auto bad =
        dw::test::run({bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--security", dir.file("no-keys")}, dir);
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.err.find("no-keys"), std::string::npos) << bad.err;
}

TEST(LabRun, BadLabFileIsOneLineAndExit2) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml"))
        << "format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-probe], restart: sometimes}\n";
    const auto r = dw::test::run({bin("dw-lab"), "run", "--lab", dir.file("lab.yaml")}, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(dw::test::lines(r.err).size(), 1u) << r.err;
    EXPECT_NE(r.err.find("lab.yaml:3"), std::string::npos) << r.err;
}

// The lab across two hosts: network namespaces joined by a veth pair. The launcher, stand agent,
// mocap bridge and recorder run in host A; the planner is started in host B through its launch
// prefix (as ssh would on a real lab). Needs root; skipped otherwise.
namespace {
int sh(const std::string& c) { return std::system((c + " >/dev/null 2>&1").c_str()); }

// Two hosts: network namespaces a and b joined by a veth pair (multicast routed over it), removed
// when this goes out of scope. The launcher runs in a; a lab file's host `hostb` launches in b.
struct TwoHosts {
    std::string id = std::to_string(::getpid() % 100000), a = "dwla" + id, b = "dwlb" + id;
    std::string net = "10.232." + std::to_string(::getpid() % 250);
    bool up() const {
        for (const auto& s : std::vector<std::string>{
                 "ip netns add " + a, "ip netns add " + b, "ip link add " + a + " type veth peer name " + b,
                 "ip link set " + a + " netns " + a, "ip link set " + b + " netns " + b,
                 "ip -n " + a + " addr add " + net + ".1/24 dev " + a,
                 "ip -n " + b + " addr add " + net + ".2/24 dev " + b, "ip -n " + a + " link set " + a + " up",
                 "ip -n " + b + " link set " + b + " up", "ip -n " + a + " link set lo up",
                 "ip -n " + b + " link set lo up", "ip -n " + a + " route add 224.0.0.0/4 dev " + a,
                 "ip -n " + b + " route add 224.0.0.0/4 dev " + b}) {
            if (sh(s) != 0) {
                ADD_FAILURE() << s;
                return false;
            }
        }
        return true;
    }
    ~TwoHosts() {
        sh("ip netns del " + a);
        sh("ip netns del " + b);
    }
    std::string host_b() const { return "hostb: {launch: [ip, netns, exec, " + b + "]}"; }
    dw::test::RunResult run_lab(const dw::test::TempDir& dir) const {
        return dw::test::run({"ip", "netns", "exec", a, bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"),
                              "--run-dir", dir.file("run"), "--profile", "lab", "--insecure", "--transport", "udp",
                              "--domain", std::to_string(dw::test::test_domain())},
                             dir, 300000ms);
    }
};

// The clock offsets (ms) a process's status lines show, in order ("clock   +49.99 ms ±0.09").
std::vector<double> status_clock_ms(const std::string& text, const std::string& process) {
    std::vector<double> shown;
    std::istringstream lines(text);
    for (std::string line; std::getline(lines, line);) {
        const auto at = line.find("clock ");
        if (!line.starts_with("  " + process + " ") || at == std::string::npos) continue;
        const std::string value = line.substr(at + 6);
        if (value.starts_with("not measured")) continue;  // before the first exchange with the time service
        char* end = nullptr;
        const double ms = std::strtod(value.c_str(), &end);
        if (end == value.c_str()) {
            ADD_FAILURE() << "a status line's clock is neither a number nor 'not measured': '" << line << "'";
            continue;
        }
        shown.push_back(ms);
    }
    return shown;
}
}  // namespace

TEST(LabRun, AcrossTwoHostsInNetworkNamespaces) {
    if (::geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
    TwoHosts hosts;
    ASSERT_TRUE(hosts.up());
    const std::string b = hosts.b;
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << lab_text(hosts.host_b(), "hostb");
    const auto r = hosts.run_lab(dir);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("DONE: 2 of 2 legs"), std::string::npos) << r.out;
    EXPECT_NE(r.err.find("started planner on hostb"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("ip netns exec " + b), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("@hostb"), std::string::npos) << r.err;  // its status line, heard across the veth
    EXPECT_TRUE(std::filesystem::exists(dir.file("run/exp.mcap")));
}

// Issue 19: a clock error hidden in the stand agent on another host (--clock-offset 0.05) is
// measured live by the clock service within 2 ms, shown in the status lines, recorded, and taken
// out of the exported flight's stamps (kept with --raw-stamps).
TEST(LabRun, MeasuresAClockErrorHiddenOnAnotherHost) {
    if (::geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
    TwoHosts hosts;
    ASSERT_TRUE(hosts.up());
    dw::test::TempDir dir;
    std::string lab = lab_text(hosts.host_b(), "local");
    const auto flaky = lab.find("  - name: flaky");
    lab.erase(flaky, lab.find("  - name: planner") - flaky);
    const std::string stand = "    run: [dw-stand-agent, run, --sim]\n";
    lab.replace(lab.find(stand), stand.size(),
                "    host: hostb\n    run: [dw-stand-agent, run, --sim, --clock-offset, \"0.05\"]\n");
    std::ofstream(dir.file("lab.yaml")) << lab;
    const auto r = hosts.run_lab(dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto shown = status_clock_ms(r.err, "stand_agent");
    ASSERT_FALSE(shown.empty()) << "the status lines show the stand agent's offset\n" << r.err;
    EXPECT_NEAR(shown.back(), 50.0, 2.0) << r.err;

    std::map<std::uint16_t, std::string> topics;
    std::vector<double> measured;
    dw::mcap::read_file(dir.file("run/exp.mcap"),
                        {.on_channel = [&](const dw::mcap::Channel& c) { topics[c.id] = c.topic; },
                         .on_message =
                             [&](const dw::mcap::Message& m) {
                                 if (!topics[m.channel_id].ends_with("/processes/status")) return;
                                 dw::msg::ProcessStatus s;
                                 ASSERT_TRUE(dw::recordings::deserialize(m.data, s));
                                 if (s.process() == "stand_agent" && s.clock_uncertainty_s() >= 0)
                                     measured.push_back(s.clock_offset_s());
                             }});
    ASSERT_GT(measured.size(), 10u) << "the recording holds the stand agent's measured offsets";
    EXPECT_NEAR(measured.back(), 0.05, 0.002);

    const auto corrected = dw::recordings::flight_from_recording(dir.file("run/exp.mcap"), {});
    const auto raw = dw::recordings::flight_from_recording(dir.file("run/exp.mcap"), {.raw_stamps = true});
    const auto applied = nlohmann::json::parse(corrected.meta.extra_json)["clock_offsets_applied_s"];
    EXPECT_NEAR(applied["stand_agent"].get<double>(), 0.05, 0.002) << applied;
    EXPECT_TRUE(nlohmann::json::parse(raw.meta.extra_json)["clock_offsets_applied_s"].empty());
    ASSERT_EQ(corrected.wrench.size(), raw.wrench.size());
    const double shift =
        (raw.wrench.front().t + nlohmann::json::parse(raw.meta.extra_json)["epoch_unix_s"].get<double>()) -
        (corrected.wrench.front().t + nlohmann::json::parse(corrected.meta.extra_json)["epoch_unix_s"].get<double>());
    EXPECT_NEAR(shift, 0.05, 0.002) << "the wrench stamps moved onto the recorder's clock";
}

namespace {

// Waits (bounded) until `file` holds `text`; returns the file's text then.
std::string await_text(const std::string& file, const std::string& text, std::chrono::seconds limit = 120s) {
    const auto until = std::chrono::steady_clock::now() + limit;
    std::string now;
    while (std::chrono::steady_clock::now() < until) {
        if (std::filesystem::exists(file) && (now = dw::read_file(file)).find(text) != std::string::npos) return now;
        std::this_thread::sleep_for(100ms);
    }
    ADD_FAILURE() << file << " never said '" << text << "':\n" << now;
    return now;
}

// Every header.seq recorded of one topic, over several files, and whether each file read whole.
std::vector<std::uint64_t> recorded_seqs(const std::vector<std::string>& files, const std::string& suffix) {
    std::vector<std::uint64_t> seqs;
    for (const auto& file : files) {
        std::map<std::uint16_t, std::string> topics;
        const auto r =
            dw::mcap::read_file(file, {.on_channel = [&](const dw::mcap::Channel& c) { topics[c.id] = c.topic; },
                                       .on_message =
                                           [&](const dw::mcap::Message& m) {
                                               if (topics[m.channel_id].ends_with("/" + suffix))
                                                   seqs.push_back(m.sequence);
                                           }});
        EXPECT_FALSE(r.error) << file << ": " << *r.error;
        EXPECT_TRUE(r.complete) << file << " does not read whole";
    }
    std::sort(seqs.begin(), seqs.end());
    return seqs;
}

}  // namespace

// Issue 19: the recorder killed (SIGKILL) mid-experiment with `restart: on-failure`. The launcher
// restarts it with --keep-existing: it writes exp_0001.mcap and recovers the killed one's exp.mcap
// in place; the planner waits out the gap (--rejoin-grace) and ends DONE; every file reads whole
// and the stand's wrench misses at most a second more than the recorder was down.
namespace {
// Past the recorder's own downtime (its heartbeat back), what its readers may still miss while the
// stand's writer is matched to them.
constexpr double kRecorderRejoinSlackS = 1.0;
}  // namespace
TEST(LabRun, ARecorderKilledMidExperimentIsRestartedIntoANewFileAndEveryFileReads) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << R"(format: downwash-lab/1
processes:
  - name: stand_agent
    run: [dw-stand-agent, run, --sim]
  - name: mocap_bridge
    run: [dw-mocap-bridge, --sim, --sim-vehicles, v1]
  - name: recorder
    run: [dw-recorder, record, --out, "{run_dir}/exp.mcap", --quiet, --no-fsync, --flush-interval, "0.25"]
    restart: on-failure
  - name: planner
    run: [dw-planner, run, --formation, single, --legs, "4", --altitudes, "0.5", --speed, "1.0", --rejoin-grace, "10"]
    experiment: true
)";
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "labkill" + std::to_string(::getpid());
    // When the restarted recorder says it is running (its readers made), on this test's clock.
    dw::dds::Participant watcher(cfg, "watcher");
    std::atomic<pid_t> recorder{0};
    std::atomic<std::int64_t> back_ns{0};
    const auto now_ns = [] { return dw::SystemClock::instance().monotonic_ns(); };
    dw::dds::Reader<dw::msg::ProcessStatus> heartbeats(
        watcher, dw::dds::topics::process_status, [&](const dw::msg::ProcessStatus& s, const dw::dds::SampleMeta&) {
            if (s.process() == "recorder" && recorder != 0 && s.pid() != recorder &&
                s.state() == dw::msg::PROC_RUNNING && back_ns == 0)
                back_ns = now_ns();
        });
    dw::Subprocess lab({{bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"), "--domain",
                         std::to_string(cfg.domain), "--namespace", cfg.ns},
                        dir.file("lab.out"),
                        dir.file("lab.err"),
                        {}});
    const std::string started = await_text(dir.file("lab.err"), "started recorder on local (pid ");
    await_text(dir.file("run/logs/planner.log"), "flying 4 legs");
    std::this_thread::sleep_for(3s);
    const auto at = started.find("started recorder on local (pid ") + std::strlen("started recorder on local (pid ");
    recorder = std::stoi(started.substr(at));
    const auto killed_ns = now_ns();
    ASSERT_EQ(::kill(recorder, SIGKILL), 0);
    const auto status = lab.wait_for(300000ms);
    ASSERT_TRUE(status) << "dw-lab did not end";
    const std::string out = dw::read_file(dir.file("lab.out")), err = dw::read_file(dir.file("lab.err"));
    ASSERT_EQ(*status, 0) << err;
    EXPECT_NE(out.find("DONE: 4 of 4 legs"), std::string::npos) << out << err;
    EXPECT_NE(err.find("restarting recorder (1 of 3)"), std::string::npos) << err;
    EXPECT_NE(dw::read_file(dir.file("run/logs/recorder.log")).find("recovered " + dir.file("run/exp.mcap")),
              std::string::npos)
        << dw::read_file(dir.file("run/logs/recorder.log"));
    const auto seqs = recorded_seqs({dir.file("run/exp.mcap"), dir.file("run/exp_0001.mcap")}, "stand/wrench");
    ASSERT_GT(seqs.size(), 100u);
    std::uint64_t gap = 0;
    for (std::size_t i = 1; i < seqs.size(); ++i) gap = std::max(gap, seqs[i] - seqs[i - 1] - 1);
    const double gap_s = static_cast<double>(gap) / 80.0;  // the simulated stand publishes at 80 Hz
    // What is lost is what no recorder was there for: the restart itself (dw-lab seeing the exit,
    // the new process, its discovery) takes 0.2-0.4 s alone and seconds on a loaded machine (a
    // fixed 1 s bound failed at 4.1 s in CI), so the bound is the time the recorder was down.
    ASSERT_NE(back_ns.load(), 0) << "the restarted recorder never said it was running";
    const double down_s = dw::to_seconds(back_ns - killed_ns);
    std::printf(
        "stand/wrench: %zu samples recorded in two files, the longest run missing %llu samples (%.2f s); "
        "the recorder was down %.2f s\n",
        seqs.size(), static_cast<unsigned long long>(gap), gap_s, down_s);
    EXPECT_LE(gap_s, down_s + kRecorderRejoinSlackS)
        << "more of the stand's wrench lost than while the recorder was down";
}

// Issue 19: a 2 s network partition of the stand's host (its veth down, then up again). The lab's
// decision: a required process gone for less than the planner's --rejoin-grace is waited out (the
// experiment ends DONE); for longer, or without a grace, it aborts (the stand-agent-killed test).
// The recording says where the gap was: the "gaps" metadata names the stand's silence.
TEST(LabRun, ATwoSecondPartitionOfTheStandsHostIsWaitedOutAndTheRecordingSaysWhere) {
    if (::geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
    TwoHosts hosts;
    ASSERT_TRUE(hosts.up());
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << "format: downwash-lab/1\nhosts:\n  local: {}\n  " << hosts.host_b() << R"(
processes:
  - name: stand_agent
    host: hostb
    run: [dw-stand-agent, run, --sim]
  - name: mocap_bridge
    run: [dw-mocap-bridge, --sim, --sim-vehicles, v1]
  - name: recorder
    run: [dw-recorder, record, --out, "{run_dir}/exp.mcap", --quiet, --no-fsync]
  - name: planner
    run: [dw-planner, run, --formation, single, --legs, "4", --altitudes, "0.5", --speed, "1.0", --rejoin-grace, "10"]
    experiment: true
)";
    dw::Subprocess lab({{"ip", "netns", "exec", hosts.a, bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"),
                         "--run-dir", dir.file("run"), "--profile", "lab", "--insecure", "--transport", "udp",
                         "--domain", std::to_string(dw::test::test_domain())},
                        dir.file("lab.out"),
                        dir.file("lab.err"),
                        {}});
    await_text(dir.file("run/logs/planner.log"), "flying 4 legs");
    std::this_thread::sleep_for(2s);
    // How long the link was cut: 2 s, plus what the commands that cut and mend it take (on a busy
    // machine a shell's start is not instant).
    const auto cut_from = std::chrono::steady_clock::now();
    ASSERT_EQ(sh("ip -n " + hosts.b + " link set " + hosts.b + " down"), 0);
    std::this_thread::sleep_for(2s);
    ASSERT_EQ(sh("ip -n " + hosts.b + " link set " + hosts.b + " up"), 0);
    const double cut_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - cut_from).count();
    sh("ip -n " + hosts.b + " route add 224.0.0.0/4 dev " + hosts.b);  // a link going down takes its routes
    sh("ip -n " + hosts.a + " route add 224.0.0.0/4 dev " + hosts.a);
    const auto status = lab.wait_for(300000ms);
    ASSERT_TRUE(status) << "dw-lab did not end";
    const std::string out = dw::read_file(dir.file("lab.out")), err = dw::read_file(dir.file("lab.err"));
    ASSERT_EQ(*status, 0) << err;
    EXPECT_NE(out.find("DONE: 4 of 4 legs"), std::string::npos) << out << err;
    const std::string planner = dw::read_file(dir.file("run/logs/planner.log"));
    EXPECT_NE(planner.find("stand_agent is back"), std::string::npos) << planner;

    std::map<std::string, std::string> gaps;
    dw::mcap::read_file(dir.file("run/exp.mcap"), {.on_metadata = [&](const dw::mcap::Metadata& m) {
                            if (m.name == "gaps") gaps = m.entries;
                        }});
    std::string wrench;
    for (const auto& [topic, text] : gaps)
        if (topic.ends_with("/stand/wrench")) wrench = text;
    ASSERT_FALSE(wrench.empty()) << "no gap of stand/wrench stored";
    double longest = 0;
    for (std::size_t at = wrench.find(" ("); at != std::string::npos; at = wrench.find(" (", at + 1))
        longest = std::max(longest, std::stod(wrench.substr(at + 2)));
    std::printf("stand/wrench gaps: %s (the link cut for at most %.3f s)\n", wrench.c_str(), cut_s);
    EXPECT_GE(longest, 1.5) << wrench;
    EXPECT_LE(longest, cut_s + 2.0) << wrench << "; the link cut for at most " << cut_s << " s";
}

TEST(LabDemo, QuickDemoMakesEverythingItsIndexLinks) {
    dw::test::TempDir dir;
    const auto r =
        // --jobs 1: the study trains one model at a time, so the demo takes one thread's slots.
        dw::test::run({bin("dw-lab"), "demo", "--quick", "--jobs", "1", "--out", dir.file("demo"), "--domain",
                       std::to_string(dw::test::test_domain()), "--namespace", "demo" + std::to_string(::getpid()),
                       "--viewer-port", "0"},
                      dir, 900000ms);
    ASSERT_EQ(r.status, 0) << r.err;
    // Issue 72: the viewer ran beside the experiments and its address was printed.
    EXPECT_NE(r.out.find("watch the lab live: open http://127.0.0.1:"), std::string::npos) << r.out;
    const std::string index = dw::read_file(dir.file("demo/index.md"));
    for (const char* f :
         {"recordings/single.mcap", "recordings/lf3.mcap", "flights/lf3", "study/table.md", "study/models",
          "recorded/table.md", "study/maps/leader_follower3.png", "recorded/lf3_map.png", "explain/report.md",
          "explain/report.json", "explain/residuals_before.png"}) {
        EXPECT_NE(index.find(f), std::string::npos) << f;
        EXPECT_TRUE(std::filesystem::exists(dir.file(std::string("demo/") + f))) << f;
    }
    for (const char* m : {"naive_linear.json", "learnt_linear.json", "deep_sets.json"})
        EXPECT_TRUE(std::filesystem::exists(dir.file(std::string("demo/study/models/") + m))) << m;
    const auto report = nlohmann::json::parse(dw::read_file(dir.file("demo/explain/report.json")));
    // Issue 19: the hidden effect ran in the lab (the stand agent's clock 0.1 s ahead); the explainer
    // read the recording and fitted it; the time service's live measurement stands beside the fit.
    ASSERT_EQ(report["explained_by"][0], "clock_offset") << report.dump(1);
    EXPECT_NEAR(report["clock_offset_measured"]["offset_s"].get<double>(), 0.1, 0.005) << report.dump(1);
    for (const auto& c : report["candidates"]) {
        if (c["effect"] != "clock_offset") continue;
        EXPECT_NEAR(c["params"]["offset_s"].get<double>(), 0.1, 0.02) << c.dump();
        EXPECT_EQ(c["measured"]["offset_s"], report["clock_offset_measured"]["offset_s"]);
        // Issue 68, item 5: what the fitted number estimates is the clock plus the stand's own
        // pipeline delay (the simulated air's lag, measured live by the stand): the sum is met.
        const double delay = report["clock_offset_measured"]["pipeline_delay_s"].get<double>();
        EXPECT_GT(delay, 0.0) << report.dump(1);
        EXPECT_LT(delay, 0.03) << report.dump(1);
        EXPECT_NEAR(c["params"]["offset_s"].get<double>(), c["measured"]["expected_s"].get<double>(), 0.005)
            << c.dump();
    }
    EXPECT_NE(dw::read_file(dir.file("demo/explain/report.md")).find("measured beside fitted"), std::string::npos);
    EXPECT_NE(r.out.find("experiments: DONE, DONE"), std::string::npos) << r.out;
    // Issue 73, item 6: where its time went, step by step, printed and in index.md.
    EXPECT_NE(r.out.find("where the time went:"), std::string::npos) << r.out;
    const auto table = index.find("## Where the time went");
    ASSERT_NE(table, std::string::npos) << index;
    for (const char* step : {"| flying single", "| flying leader_follower3", "| training ", "| the models on the",
                             "| explaining ", "| writing index.md"})
        EXPECT_NE(index.find(step, table), std::string::npos) << step;
}

// Issue 17: the lab file is read through core/keys like every configuration; a misspelt key is
// named, not the missing key it leaves behind, and a restart policy lists the known ones.
TEST(LabFile, AMisspeltKeyIsNamedBeforeWhatItsAbsenceBreaks) {
    EXPECT_EQ(error_of("format: downwash-lab/1\nprocesses:\n  - {name: a, rnu: [dw-probe, list]}\n"),
              "lab.yaml:3:15: processes[0].rnu: unknown key 'rnu' (known: experiment, host, name, restart, run)");
    EXPECT_EQ(error_of("format: downwash-lab/1\nprocesses:\n  - {name: a, run: [dw-probe], restart: always}\n"),
              "lab.yaml:3:41: processes[0].restart: unknown restart policy 'always' (expected never or on-failure)");
    EXPECT_EQ(error_of("format: downwash-lab/1\nhosts:\n  pi: {launch: ssh}\nprocesses: []\n"),
              "lab.yaml:3:16: hosts.pi.launch: expected a list of words");
    const auto lab = dw::lab::parse_lab(
        "format: downwash-lab/1\nvars: {x: \"1\"}\nhosts:\n  pi: {launch: [ssh, pi], bin: /opt}\n  mocap-pc:\n"
        "processes:\n  - {name: a, host: pi, run: [dw-probe, list], restart: on-failure}\n",
        "ok.yaml");
    EXPECT_EQ(lab.vars.at("x"), "1");
    EXPECT_EQ(lab.hosts.at("pi").launch, (std::vector<std::string>{"ssh", "pi"}));
    EXPECT_EQ(lab.hosts.at("pi").name, "pi");
    EXPECT_EQ(lab.hosts.count("mocap-pc"), 1u);
    EXPECT_EQ(lab.hosts.count("local"), 1u) << "always there";
    EXPECT_EQ(lab.processes.at(0).restart, dw::lab::Restart::on_failure);
}

// Issue 14: a process name that is a path wrote its log outside the run folder; a lab file that
// starts dw-lab started itself without end.
TEST(LabFile, ProcessNamesAreNotPathsAndTheLauncherIsNotAProcess) {
    for (const char* name : {"../../escape", "a/b", ".hidden", ""}) {
        const std::string e = error_of(std::string("format: downwash-lab/1\nprocesses:\n  - {name: \"") + name +
                                       "\", run: [dw-probe, list], experiment: true}\n");
        EXPECT_NE(e.find("is not a process name"), std::string::npos) << name << ": " << e;
    }
    const std::string e =
        error_of("format: downwash-lab/1\nprocesses:\n  - {name: again, run: [dw-lab, run, --lab, lab.yaml]}\n");
    EXPECT_NE(e.find("cannot start the launcher"), std::string::npos) << e;
    EXPECT_EQ(error_of("format: downwash-lab/1\nprocesses:\n  - {name: probe-1.a_b, run: [dw-probe, list]}\n"), "");
}

// Issue 19, the soak's judgement: flat memory and no loss pass; growth after the warm-up, a
// process's losses or the recording's fail, each named.
TEST(LabSoak, JudgesMemoryGrowthAndLossesFromTheLaunchersSamples) {
    std::vector<dw::lab::ResourceRow> rows;
    for (int i = 0; i <= 36; ++i) {
        const double t = 5.0 * i;
        rows.push_back(
            {t, "flat", 10, {i == 0 ? 2.0 : 30.0 + 0.01 * (i % 2), 0.1 * t}, 0});          // start-up jump, then flat
        rows.push_back({t, "leaky", 11, {20.0 + 0.02 * t, 0.05 * t}, i >= 30 ? 3u : 0u});  // 1.2 MB/min, loses 3 late
    }
    const auto t = dw::lab::trends(rows);
    ASSERT_EQ(t.size(), 2u);
    EXPECT_EQ(t[0].process, "flat");
    EXPECT_NEAR(t[0].rss_slope_mb_per_min, 0.0, 0.01) << "the warm-up's jump is left out";
    EXPECT_NEAR(t[0].cpu_percent, 10.0, 1e-9);
    EXPECT_NEAR(t[1].rss_slope_mb_per_min, 1.2, 1e-9);
    EXPECT_EQ(t[1].lost, 3u);
    EXPECT_EQ(dw::lab::judge({t[0]}, 0), "");
    const std::string why = dw::lab::judge(t, 5);
    EXPECT_NE(why.find("leaky's memory grows 1.2 MB/min"), std::string::npos) << why;
    EXPECT_NE(why.find("leaky lost 3 samples"), std::string::npos) << why;
    EXPECT_NE(why.find("the recording is missing 5 samples"), std::string::npos) << why;
    EXPECT_EQ(why.find("flat"), std::string::npos) << why;

    // A restarted process is a new instance, judged on its own; a restart fails the soak; a run too
    // short to judge memory says so instead of passing.
    std::vector<dw::lab::ResourceRow> restarted;
    for (int i = 0; i <= 36; ++i) restarted.push_back({5.0 * i, "p", i < 20 ? 20 : 21, {10.0, 0.0}, 0});
    const auto r = dw::lab::trends(restarted);
    ASSERT_EQ(r.size(), 2u);
    EXPECT_EQ(r[1].pid, 21);
    EXPECT_EQ(dw::lab::restarts_text({{"p", 1}}), "p restarted 1 time(s)");
    const auto short_run = dw::lab::trends({{0, "q", 5, {1, 0}, 0}, {40, "q", 5, {1, 0}, 0}});
    EXPECT_NE(dw::lab::judge(short_run, 0).find("q (pid 5): 1 samples after the warm-up, too few"), std::string::npos)
        << dw::lab::judge(short_run, 0);
}

// Issue 19: the soak CI runs (3 minutes; docs/BENCHMARKS.md has a 30-minute one): every process
// sampled through the run, memory flat after the warm-up, nothing lost, the charts drawn. Not
// shorter: over 2 minutes the recorder's memory, still filling its first chunks, rose 0.51 MB/min
// after the warm-up (limit 0.5; issue 40). It starts first and runs alone (a heavy test's slots):
// with other tests beside it the recorder grew 1.0-1.25 MB/min in three fresh clones of four.
TEST(LabSoak, ThreeMinutesOfTheSimulatedLabKeepMemoryFlatAndLoseNothing) {
    dw::test::TempDir dir;
    const auto r =
        dw::test::run({bin("dw-lab"), "soak", "--minutes", "3", "--out", dir.file("soak"), "--domain",
                       std::to_string(dw::test::test_domain()), "--namespace", "soak" + std::to_string(::getpid())},
                      dir, 900000ms);
    std::printf("%s\n", r.out.c_str());
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    const auto j = nlohmann::json::parse(dw::read_file(dir.file("soak/soak.json")));
    EXPECT_EQ(j["verdict"], "pass");
    EXPECT_EQ(j["phase"], "DONE");
    EXPECT_GE(j["sampled_s"].get<double>(), 150.0);
    ASSERT_EQ(j["processes"].size(), 5u);
    for (const auto& p : j["processes"]) {
        EXPECT_GE(p["samples"].get<int>(), 30) << p;
        EXPECT_EQ(p["lost"].get<std::uint64_t>(), 0u) << p;
        EXPECT_LE(p["rss_slope_mb_per_min"].get<double>(), dw::lab::kRssSlopeLimitMbPerMin) << p;
    }
    EXPECT_EQ(j["recorder_lost"].get<std::uint64_t>(), 0u);
    for (const char* png : {"soak/soak_rss.png", "soak/soak_cpu.png"})
        EXPECT_GT(std::filesystem::file_size(dir.file(png)), 1000u) << png;
}

namespace {
std::string proc_text(const std::filesystem::path& p) {  // "" once the process is gone
    std::ifstream in(p);
    std::ostringstream out;
    out << in.rdbuf();
    return out.str();
}

// The running processes whose command line holds every one of `words`.
std::vector<std::filesystem::path> processes_with(const std::vector<std::string>& words) {
    std::vector<std::filesystem::path> found;
    std::error_code ec;
    for (const auto& e : std::filesystem::directory_iterator("/proc", ec)) {
        std::string cmdline = proc_text(e.path() / "cmdline");
        std::replace(cmdline.begin(), cmdline.end(), '\0', ' ');
        if (!cmdline.empty() && std::all_of(words.begin(), words.end(),
                                            [&](const std::string& w) { return cmdline.find(w) != std::string::npos; }))
            found.push_back(e.path());
    }
    return found;
}

// The largest resident set (VmHWM, MB) of the running process whose command line holds every one of
// `words`, sampled until `stop`; 0 if none was seen.
double peak_rss_mb_while(const std::vector<std::string>& words, const std::stop_token& stop) {
    double peak = 0;
    while (!stop.stop_requested()) {
        for (const auto& p : processes_with(words)) {
            std::istringstream status(proc_text(p / "status"));
            for (std::string line; std::getline(status, line);)
                if (line.rfind("VmHWM:", 0) == 0) peak = std::max(peak, std::stod(line.substr(6)) / 1024.0);
        }
        std::this_thread::sleep_for(200ms);
    }
    return peak;
}

// The bridge's resident memory under a hostile Motive (docs/HOSTILE_INPUT.md; measured 2026-12-06:
// see the figure there).
constexpr double kBridgePeakMb = 150;

// Issue 70, the hostile-wire suite: the simulated lab flies (its mocap bridge started with
// `bridge_args` more) while `dw-probe hostile` publishes malformed samples on every lab topic, with
// each topic's own QoS (an unknown encapsulation, cut short, and on the sensor topics that command
// nothing absurd words: NaN, ±inf, 1e300). Every process survives (each stops with status 0), the
// experiment ends DONE or ABORTED with a reason, nothing the planner sends a vehicle is non-finite
// or outside the room (read on vehicles/setpoint, where the simulated vehicles read it), and the
// bridge's memory stays under kBridgePeakMb.
void fly_the_hostile_lab(const std::string& bridge_args) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("lab.yaml")) << R"(format: downwash-lab/1
processes:
  - name: stand_agent
    run: [dw-stand-agent, run, --sim]
  - name: mocap_bridge
    run: [dw-mocap-bridge, --sim, --sim-vehicles, v1)" +
                                               bridge_args + R"(]
  - name: recorder
    run: [dw-recorder, record, --out, "{run_dir}/exp.mcap", --quiet, --no-fsync]
  - name: predictor
    run: [dw-predictor, run, --model, ")" + std::string(DW_SOURCE_DIR) +
                                               R"(/config/physics.example.yaml"]
  - name: planner
    run: [dw-planner, run, --formation, single, --legs, "2", --altitudes, "0.5", --speed, "1.0"]
    experiment: true
)";
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "hostile" + std::to_string(::getpid());
    dw::dds::Participant watcher(cfg, "watcher");
    std::mutex m;
    std::vector<dw::msg::VehicleSetpoint> sent;
    dw::dds::Reader<dw::msg::VehicleSetpoint> setpoints(
        watcher, dw::dds::topics::vehicle_setpoint, [&](const dw::msg::VehicleSetpoint& s, const dw::dds::SampleMeta&) {
            std::lock_guard lock(m);
            sent.push_back(s);
        });
    std::stop_source stop_watching;
    double bridge_peak_mb = 0;
    std::jthread memory([&] {
        bridge_peak_mb = peak_rss_mb_while({"dw-mocap-bridge", cfg.ns}, stop_watching.get_token());
    });
    const std::vector<std::string> dds{"--domain", std::to_string(cfg.domain), "--namespace", cfg.ns};
    const auto run = fly_under_hostile_probe(
        dir, {bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run")}, {"--rate", "20"}, dds,
        300000ms, "DONE: 2 of 2 legs", {"stand_agent", "mocap_bridge", "recorder", "predictor"});
    stop_watching.request_stop();
    memory.join();
    ASSERT_TRUE(run.ended) << "dw-lab did not end";
    EXPECT_NE(run.err.find("planner ended with status " + std::string(run.done ? "0" : "1")), std::string::npos)
        << run.err;
    EXPECT_NE(run.probe_out.find("stand/wrench garbage"), std::string::npos);
    EXPECT_GT(bridge_peak_mb, 0) << "the bridge was never seen running";
    EXPECT_LT(bridge_peak_mb, kBridgePeakMb);
    std::lock_guard lock(m);
    ASSERT_GT(sent.size(), 100u);
    const dw::planner::Geofence room;
    for (const auto& s : sent) {
        const dw::physics::Vec3 x(s.position_m().x(), s.position_m().y(), s.position_m().z());
        ASSERT_TRUE(room.contains(x, dw::planner::Geofence::kTolerance_m) && std::isfinite(s.yaw_rad()))
            << "sent " << x.transpose() << " yaw " << s.yaw_rad() << "\n"
            << run.err;
    }
    std::printf("%s%zu setpoints checked, the bridge's peak %.0f MB; %s\n", run.out.c_str(), sent.size(),
                bridge_peak_mb, run.done ? "DONE" : "ABORTED");
}
}  // namespace

TEST(HostileWire, TheLabUnderMalformedSamplesOnEveryTopicSendsNoAbsurdCommand) { fly_the_hostile_lab(""); }

// ... and under a hostile Motive too (its emulated NatNet server, the same client a real Motive
// meets): ten new rigid-body ids every frame, a frozen frame clock, and every fifth frame one more
// packet cut short, oversized, or of NaN, ±inf and ±3.4e38 bodies and timestamp.
TEST(HostileWire, TheLabUnderAHostileMotiveAndMalformedSamplesSendsNoAbsurdCommand) {
    fly_the_hostile_lab(", --sim-new-ids-per-frame, \"10\", --sim-frozen-clock, --sim-hostile-packets");
}

// Issue 70: a keystore whose one identity's permissions, signed by the lab's own CA, hold `<dds/>`
// crashed that process inside Fast DDS (SIGSEGV, nothing on stderr). In a lab run now: that process
// (the predictor, which the experiment can do without) exits 2, dw-lab's line says why naming the
// file, the others fly the experiment to its end and stop with status 0, and nothing is left running.
TEST(HostileWire, ALabWithASignedButMalformedPermissionsFileSaysWhichFileAndFliesOn) {
    dw::test::TempDir dir;
    ASSERT_NO_FATAL_FAILURE(write_secure_lab(dir));
    const std::string perm = dw::dds::KeystorePaths{dir.file("keys")}.permissions("predictor");
    dw::security::sign_document(dir.file("keys"), "<dds/>", perm);
    const std::string ns = "badperm" + std::to_string(::getpid());
    const auto r =
        dw::test::run({bin("dw-lab"), "run", "--lab", dir.file("lab.yaml"), "--run-dir", dir.file("run"), "--security",
                       dir.file("keys"), "--domain", std::to_string(dw::test::test_domain()), "--namespace", ns},
                      dir, 300000ms);
    const auto said = r.err.find("predictor exited with status 2: ");
    ASSERT_NE(said, std::string::npos) << r.err;
    const std::string line = r.err.substr(said, r.err.find('\n', said) - said);
    EXPECT_NE(line.find(perm), std::string::npos) << line;
    EXPECT_NE(line.find("has no <permissions>"), std::string::npos) << line;
    EXPECT_TRUE(r.out.find("DONE: 2 of 2 legs") != std::string::npos || r.err.find("ABORTED") != std::string::npos)
        << r.out << r.err;
    for (const char* p : {"stand_agent", "mocap_bridge", "recorder"})
        EXPECT_NE(r.err.find(std::string("stopped ") + p + " (status 0)"), std::string::npos) << p << "\n" << r.err;
    EXPECT_TRUE(processes_with({ns}).empty()) << "a process of the lab outlived it";
}

// A sibling given its parent's stop is asked to stop the moment a stop is requested — not only when
// the parent gets round to destroying it — so its grace runs beside the rest of the parent's
// stopping (the demo's training beside its lab). The wait below only keeps a broken build from
// hanging; it measures nothing.
TEST(Sibling, IsAskedToStopTheMomentItsParentIs) {
    dw::test::TempDir d;
    std::stop_source stop;
    dw::Sibling emulator({"dw-natnet-emulator", "--port", "0"}, d.file("emulator.log"), 0, stop.get_token());
    ASSERT_TRUE(emulator.running()) << dw::read_file(d.file("emulator.log"));
    stop.request_stop();
    for (int i = 0; i < 3000 && emulator.running(); ++i) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    EXPECT_FALSE(emulator.running()) << "still running 30 s after the stop request";
    EXPECT_THROW(emulator.finish(stop.get_token()), dw::Stopped);
}
