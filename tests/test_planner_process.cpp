// A short experiment with the simulated stand, simulated mocap and vehicles, the recorder and the
// planner as separate processes on loopback DDS: it ends in DONE with every leg flown; killing
// the mocap bridge mid-leg ends in ABORTED with that reason and every vehicle landed.
#include <gtest/gtest.h>
#include <signal.h>

#include <deque>
#include <mutex>
#include <thread>

#include "dds/endpoint.hpp"
#include "mcap/mcap.hpp"
#include "support.hpp"

using namespace std::chrono_literals;

namespace {
struct Lab {
    dw::test::TempDir dir;
    dw::dds::DdsConfig cfg;
    std::deque<dw::Subprocess> procs;  // stable references across start()
    Lab(const std::string& tag) {
        cfg.domain = dw::test::test_domain();
        cfg.ns = tag + std::to_string(::getpid());
    }
    dw::Subprocess& start(const std::string& exe, std::vector<std::string> args, const std::string& log) {
        args.insert(args.begin(), dw::test::bin(exe));
        for (const auto& a : std::vector<std::string>{"--domain", std::to_string(cfg.domain), "--namespace", cfg.ns}) args.push_back(a);
        procs.emplace_back(dw::SpawnOptions{args, dir.file(log), dir.file(log), {}});
        return procs.back();
    }
    std::string log(const std::string& name) { return dw::read_file(dir.file(name)); }
    ~Lab() {
        for (auto& p : procs) p.stop();
    }
};
}  // namespace

TEST(Experiment, ShortExperimentEndsInDoneWithEveryLegFlown) {
    Lab lab("expdone");
    lab.start("dw-stand-agent", {"run", "--sim"}, "stand.log");
    lab.start("dw-mocap-bridge", {"--sim", "--sim-vehicles", "v1,v2"}, "mocap.log");
    lab.start("dw-recorder", {"record", "--out", lab.dir.file("exp.mcap"), "--quiet", "--no-fsync"}, "rec.log");
    auto& planner = lab.start("dw-planner", {"run", "--formation", "side_by_side", "--legs", "2", "--altitudes", "0.5",
                                            "--speed", "1.0"}, "planner.log");
    const auto status = planner.wait_for(180000ms);
    ASSERT_EQ(status, std::optional<int>(0)) << lab.log("planner.log") << lab.log("mocap.log");
    EXPECT_NE(lab.log("planner.log").find("DONE: 2 of 2 legs flown"), std::string::npos) << lab.log("planner.log");
    // The recorder saw the plan, the states through DONE, setpoints and poses.
    lab.procs[2].signal(SIGINT);
    lab.procs[2].wait_for(30000ms);
    std::map<std::string, int> counts;
    std::map<std::uint16_t, std::string> topics;
    dw::mcap::read_file(lab.dir.file("exp.mcap"), {
        .on_channel = [&](const dw::mcap::Channel& c) { topics[c.id] = c.topic; },
        .on_message = [&](const dw::mcap::Message& m) { ++counts[topics[m.channel_id]]; }});
    const std::string p = "rt/" + lab.cfg.ns + "/";
    EXPECT_EQ(counts[p + "experiment/plan"], 1);
    EXPECT_GT(counts[p + "experiment/state"], 10);
    EXPECT_GT(counts[p + "vehicles/setpoint"], 50 * 20);
    EXPECT_GT(counts[p + "mocap/frame"], 180 * 20);
    EXPECT_GT(counts[p + "stand/wrench"], 80 * 20);
}

TEST(Experiment, KillingTheMocapBridgeMidLegAbortsAndLandsEveryVehicle) {
    Lab lab("expabort");
    lab.start("dw-stand-agent", {"run", "--sim"}, "stand.log");
    auto& mocap = lab.start("dw-mocap-bridge", {"--sim", "--sim-vehicles", "v1"}, "mocap.log");
    lab.start("dw-recorder", {"record", "--out", lab.dir.file("exp.mcap"), "--quiet", "--no-fsync"}, "rec.log");
    dw::dds::Participant p(lab.cfg, "observer");
    std::mutex m;
    dw::msg::ExperimentState state;
    dw::msg::VehicleSetpoint last_setpoint;
    dw::dds::Reader<dw::msg::ExperimentState> sr(p, dw::dds::topics::experiment_state, [&](const auto& s, const auto&) {
        std::lock_guard lock(m);
        state = s;
    });
    dw::dds::Reader<dw::msg::VehicleSetpoint> spr(p, dw::dds::topics::vehicle_setpoint, [&](const auto& s, const auto&) {
        std::lock_guard lock(m);
        last_setpoint = s;
    });
    auto& planner = lab.start("dw-planner", {"run", "--formation", "single", "--legs", "4", "--altitudes", "0.5",
                                            "--speed", "1.0"}, "planner.log");
    bool mid_leg = false;
    for (int i = 0; i < 6000 && !mid_leg; ++i) {
        std::this_thread::sleep_for(10ms);
        std::lock_guard lock(m);
        mid_leg = state.phase() == dw::msg::PHASE_FLYING && state.leg_index() >= 1;
    }
    ASSERT_TRUE(mid_leg) << lab.log("planner.log");
    mocap.signal(SIGKILL);
    const auto status = planner.wait_for(60000ms);
    EXPECT_EQ(status, std::optional<int>(1)) << lab.log("planner.log");
    const std::string log = lab.log("planner.log");
    EXPECT_NE(log.find("ABORTED: mocap lost"), std::string::npos) << log;
    std::this_thread::sleep_for(300ms);
    std::lock_guard lock(m);
    EXPECT_EQ(state.phase(), dw::msg::PHASE_ABORTED);
    EXPECT_NE(state.message().find("mocap lost"), std::string::npos) << state.message();
    EXPECT_NE(state.message().find("every vehicle landed"), std::string::npos) << state.message();
    EXPECT_NEAR(last_setpoint.position_m().z(), 0.0, 1e-6);  // the last setpoint is on the floor
}
