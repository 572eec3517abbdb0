// Loopback integration: separate processes on the local profile; every topic type arrives with
// its content intact under its QoS.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "dds/topics.hpp"
#include <thread>

#include "support.hpp"

using namespace std::chrono_literals;
using dw::test::bin;
using dw::test::TempDir;

namespace {
struct Lab {
    TempDir dir;
    std::string domain = std::to_string(dw::test::test_domain());
    std::string ns = "loop" + std::to_string(::getpid());

    std::vector<std::string> probe(std::vector<std::string> args) const {
        args.insert(args.begin(), bin("dw-probe"));
        args.insert(args.end(), {"--domain", domain, "--namespace", ns});
        return args;
    }
    dw::Subprocess start(const std::vector<std::string>& args, const std::string& tag) const {
        return dw::Subprocess({probe(args), dir.file(tag + ".out"), dir.file(tag + ".err"), {}});
    }
    nlohmann::json summary(const std::string& name) const {
        return nlohmann::json::parse(dw::read_file(dir.file(name)));
    }
    std::string text(const std::string& name) const { return dw::read_file(dir.file(name)); }
};

bool is_latched(const nlohmann::json& t) {
    return t["qos"].get<std::string>().find("TRANSIENT_LOCAL") != std::string::npos;
}
}  // namespace

TEST(Loopback, EveryTopicTypeArrivesIntactUnderItsQos) {
    Lab lab;
    auto echo = lab.start(
        {"echo", "all", "--expect", "25", "--timeout", "120", "--summary", lab.dir.file("summary.json"), "--quiet"},
        "echo");
    auto pub = lab.start(
        {"pub", "all", "--count", "25", "--rate", "100", "--wait-readers", "1", "--linger", "-1", "--quiet"}, "pub");
    const auto status = echo.wait_for(180000ms);
    pub.stop();
    ASSERT_TRUE(status.has_value());
    ASSERT_EQ(*status, 0) << lab.text("echo.out") << lab.text("echo.err");
    const auto s = lab.summary("summary.json");
    ASSERT_EQ(s["topics"].size(), static_cast<std::size_t>(dw::dds::topics::kTopicCount));
    for (const auto& t : s["topics"]) {
        SCOPED_TRACE(t.dump());
        EXPECT_EQ(t["corrupt"], 0);
        EXPECT_EQ(t["intact"], 25);
        EXPECT_EQ(t["received"], 25);
        EXPECT_EQ(t["first_seq"], 0);
        EXPECT_EQ(t["last_seq"], 24);
        EXPECT_TRUE(t["in_order"].get<bool>());
        EXPECT_EQ(t["lost"], 0);
    }
    // The QoS each reader used is the topic's profile.
    std::map<std::string, std::string> qos;
    for (const auto& t : s["topics"]) qos[t["topic"]] = t["qos"];
    const std::string p = "rt/" + lab.ns + "/";
    EXPECT_EQ(qos[p + "stand/wrench"], "BEST_EFFORT VOLATILE KEEP_LAST(16)");
    EXPECT_EQ(qos[p + "mocap/frame"], "BEST_EFFORT VOLATILE KEEP_LAST(16)");
    EXPECT_EQ(qos[p + "experiment/state"], "RELIABLE TRANSIENT_LOCAL KEEP_LAST(1)");
    EXPECT_EQ(qos[p + "experiment/plan"], "RELIABLE TRANSIENT_LOCAL KEEP_LAST(1)");
    EXPECT_EQ(qos[p + "experiment/command"], "RELIABLE VOLATILE KEEP_LAST(64)");
    EXPECT_EQ(qos[p + "processes/status"], "RELIABLE VOLATILE KEEP_LAST(1)");
}

TEST(Loopback, ALateReaderGetsOnlyTheLatestLatchedState) {
    Lab lab;
    auto pub = lab.start({"pub", "all", "--count", "5", "--rate", "200", "--linger", "-1"}, "pub");
    // Wait until the publisher has written its last sample of the last topic.
    const std::string last = "rt/" + lab.ns + "/processes/status  #4";
    for (int i = 0; i < 3000 && lab.text("pub.out").find(last) == std::string::npos; ++i) {
        ASSERT_TRUE(pub.running()) << lab.text("pub.err");
        std::this_thread::sleep_for(20ms);
    }
    ASSERT_NE(lab.text("pub.out").find(last), std::string::npos);
    auto echo = lab.start({"echo", "all", "--expect", "0", "--expect-latched", "1", "--timeout", "120", "--summary",
                           lab.dir.file("late.json"), "--quiet"},
                          "echo");
    const auto status = echo.wait_for(180000ms);
    pub.stop();
    ASSERT_TRUE(status.has_value());
    ASSERT_EQ(*status, 0) << lab.text("echo.out") << lab.text("echo.err");
    int latched = 0;
    const auto late = lab.summary("late.json");
    for (const auto& t : late["topics"]) {
        SCOPED_TRACE(t.dump());
        EXPECT_EQ(t["corrupt"], 0);
        if (is_latched(t)) {
            ++latched;
            EXPECT_EQ(t["received"], 1);  // KEEP_LAST(1): the latest only
            EXPECT_EQ(t["first_seq"], 4);
        } else {
            EXPECT_EQ(t["received"], 0);  // volatile: nothing from before the reader existed
        }
    }
    EXPECT_EQ(latched, 3);
}

TEST(Loopback, QosMismatchBetweenProcessesIsReportedInOneLine) {
    Lab lab;
    auto pub = lab.start({"pub", "stand/wrench", "--count", "100000", "--rate", "50", "--quiet"}, "pub");
    auto echo = lab.start(
        {"echo", "stand/wrench", "--reliability", "reliable", "--expect", "1", "--timeout", "5", "--quiet"}, "echo");
    const auto status = echo.wait_for(120000ms);
    pub.stop();
    ASSERT_TRUE(status.has_value());
    EXPECT_EQ(*status, 1);  // nothing can arrive
    std::vector<std::string> mismatch;
    for (const auto& l : dw::test::lines(lab.text("echo.err"))) {
        if (l.find("QoS mismatch") != std::string::npos) mismatch.push_back(l);
    }
    ASSERT_EQ(mismatch.size(), 1u) << lab.text("echo.err");
    EXPECT_NE(mismatch[0].find("QoS mismatch on rt/" + lab.ns +
                               "/stand/wrench (dw::msg::WrenchStamped): "
                               "this reader requests RELIABLE"),
              std::string::npos)
        << mismatch[0];
    EXPECT_NE(mismatch[0].find("incompatible RELIABILITY"), std::string::npos) << mismatch[0];
    // The publisher saw it too, from its side.
    EXPECT_NE(lab.text("pub.err").find("this writer offers BEST_EFFORT"), std::string::npos) << lab.text("pub.err");
}

TEST(Loopback, LabLoopbackSessionSucceeds) {
    Lab lab;
    const auto r = dw::test::run({bin("dw-lab"), "loopback", "--count", "10", "--rate", "50", "--quiet", "--domain",
                                  lab.domain, "--namespace", lab.ns, "--summary", lab.dir.file("lab.json")},
                                 lab.dir);
    ASSERT_EQ(r.status, 0) << r.out << r.err;
    EXPECT_NE(r.out.find("all topics arrived intact"), std::string::npos) << r.out;
    EXPECT_TRUE(lab.summary("lab.json")["ok"].get<bool>());
}
