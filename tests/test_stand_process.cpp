// dw-stand-agent --sim as a separate process: the emulated bank feels the physics of a neighbour
// seen on the mocap topic; CALIBRATE tares it; the wrench and the status arrive over DDS.
#include <gtest/gtest.h>
#include <signal.h>

#include <mutex>
#include <thread>

#include "dds/endpoint.hpp"
#include "dds/time.hpp"
#include "physics/wrench_model.hpp"
#include "support.hpp"
#include "testkit/mocap.hpp"

using namespace std::chrono_literals;

TEST(StandAgentProcess, SimulatedStandFeelsTheNeighbourOnTheMocapTopic) {
    dw::test::TempDir dir;
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "stand" + std::to_string(::getpid());
    dw::Subprocess agent({{dw::test::bin("dw-stand-agent"), "run", "--sim", "--domain", std::to_string(cfg.domain),
                           "--namespace", cfg.ns},
                          dir.file("agent.out"),
                          dir.file("agent.err"),
                          {}});
    dw::dds::Participant p(cfg, "test");
    std::mutex m;
    std::vector<dw::msg::WrenchStamped> wrenches;
    dw::msg::StandStatus status;
    dw::dds::Reader<dw::msg::WrenchStamped> wr(p, dw::dds::topics::stand_wrench, [&](const auto& w, const auto&) {
        std::lock_guard lock(m);
        wrenches.push_back(w);
    });
    dw::dds::Reader<dw::msg::StandStatus> sr(p, dw::dds::topics::stand_status, [&](const auto& s, const auto&) {
        std::lock_guard lock(m);
        status = s;
    });
    dw::dds::Writer<dw::msg::MocapFrame> mocap(p, dw::dds::topics::mocap_frame);
    dw::dds::Writer<dw::msg::ExperimentCommand> commands(p, dw::dds::topics::experiment_command);
    ASSERT_TRUE(commands.wait_for_readers(1, 30000ms)) << dw::read_file(dir.file("agent.err"));
    ASSERT_TRUE(mocap.wait_for_readers(1, 30000ms));

    // No neighbour: tare at hover thrust.
    dw::msg::ExperimentCommand c;
    c.kind(dw::msg::CMD_CALIBRATE);
    c.issuer("test");
    commands.write(c);
    bool tared = false;
    for (int i = 0; i < 1000 && !tared; ++i) {
        std::this_thread::sleep_for(10ms);
        std::lock_guard lock(m);
        tared = !wrenches.empty() && wrenches.back().tared() && status.message() == "tared at hover thrust";
    }
    ASSERT_TRUE(tared) << dw::read_file(dir.file("agent.err"));

    // A neighbour hovering 0.3 m above: the stand reads what the physics says, within noise.
    auto frame = [&] {
        dw::msg::MocapFrame f;
        dw::testkit::add_body(f, "sufferer", 0, 0, -1.4);
        dw::testkit::add_body(f, "v1", 0, 0, -1.7);
        return f;
    };
    for (int i = 0; i < 30; ++i) {
        auto f = frame();
        mocap.write(f);
        std::this_thread::sleep_for(10ms);
    }
    {
        std::lock_guard lock(m);
        wrenches.clear();
    }
    for (int i = 0; i < 60; ++i) {
        auto f = frame();
        mocap.write(f);
        std::this_thread::sleep_for(10ms);
    }
    const dw::physics::WrenchModel model{dw::physics::PhysicsConfig{}};
    const std::array<dw::physics::Producer, 1> above{model.producer(dw::physics::Vec3(0, 0, -1.7))};
    const double expected = model.evaluate(dw::physics::Vec3(0, 0, -1.4), above)[2];
    double sum = 0;
    std::size_t n = 0;
    {
        std::lock_guard lock(m);
        for (const auto& w : wrenches) {
            sum += w.force_n().z();
            ++n;
        }
    }
    ASSERT_GT(n, 20u);
    EXPECT_NEAR(sum / static_cast<double>(n), expected, 0.05 + 0.01 * expected);
    EXPECT_EQ(status.state(), dw::msg::STAND_RUNNING);
    agent.signal(SIGINT);
    EXPECT_EQ(agent.wait_for(30000ms), std::optional<int>(0));
}
