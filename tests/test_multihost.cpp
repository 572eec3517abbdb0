// Multi-host: publisher and echo in two network namespaces ("hosts") joined by a veth pair, on the
// lab profile. Traffic stays on that pair. Needs root (CI runs as root); skipped otherwise.
#include <gtest/gtest.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include "dds/topics.hpp"

#include "support.hpp"

using namespace std::chrono_literals;
using dw::test::bin;

namespace {
int sh(const std::string& cmd) { return std::system((cmd + " >/dev/null 2>&1").c_str()); }

class TwoHosts : public ::testing::Test {
protected:
    void SetUp() override {
        if (::geteuid() != 0) GTEST_SKIP() << "network namespaces need root";
        if (sh("ip -V") != 0) GTEST_SKIP() << "iproute2 is not installed";
        const std::string id = std::to_string(::getpid() % 100000);
        a_ = "dwa" + id;
        b_ = "dwb" + id;
        const std::string net = "10.231." + std::to_string(::getpid() % 250);
        addr_a_ = net + ".1";
        addr_b_ = net + ".2";
        const std::vector<std::string> steps = {
            "ip netns add " + a_,
            "ip netns add " + b_,
            "ip link add " + a_ + " type veth peer name " + b_,
            "ip link set " + a_ + " netns " + a_,
            "ip link set " + b_ + " netns " + b_,
            "ip -n " + a_ + " addr add " + addr_a_ + "/24 dev " + a_,
            "ip -n " + b_ + " addr add " + addr_b_ + "/24 dev " + b_,
            "ip -n " + a_ + " link set " + a_ + " up",
            "ip -n " + b_ + " link set " + b_ + " up",
            "ip -n " + a_ + " link set lo up",
            "ip -n " + b_ + " link set lo up",
            // Multicast discovery leaves by the veth, the only way out of each namespace.
            "ip -n " + a_ + " route add 224.0.0.0/4 dev " + a_,
            "ip -n " + b_ + " route add 224.0.0.0/4 dev " + b_,
        };
        for (const auto& s : steps) ASSERT_EQ(sh(s), 0) << s;
        created_ = true;
    }
    void TearDown() override {
        if (!created_) return;
        sh("ip netns del " + a_);
        sh("ip netns del " + b_);
    }

    std::vector<std::string> in(const std::string& ns, std::vector<std::string> args) const {
        args.insert(args.begin(), {"ip", "netns", "exec", ns});
        return args;
    }

    // Echo in host A, publisher in host B, over UDP (shared memory cannot cross hosts).
    void expect_delivery(const std::vector<std::string>& dds_args) {
        const std::string domain = std::to_string(dw::test::test_domain());
        std::vector<std::string> echo_args{
            bin("dw-probe"),           "echo",    "all",      "--expect", "10", "--timeout", "120", "--summary",
            dir_.file("summary.json"), "--quiet", "--domain", domain};
        std::vector<std::string> pub_args{
            bin("dw-probe"),  "pub", "all",      "--count", "10",      "--rate",   "50",  "--wait-readers", "1",
            "--wait-timeout", "120", "--linger", "-1",      "--quiet", "--domain", domain};
        echo_args.insert(echo_args.end(), dds_args.begin(), dds_args.end());
        pub_args.insert(pub_args.end(), dds_args.begin(), dds_args.end());
        dw::Subprocess echo({in(a_, echo_args), dir_.file("echo.out"), dir_.file("echo.err"), {}});
        dw::Subprocess pub({in(b_, pub_args), dir_.file("pub.out"), dir_.file("pub.err"), {}});
        const auto status = echo.wait_for(180000ms);
        pub.stop();
        ASSERT_TRUE(status.has_value());
        ASSERT_EQ(*status, 0) << dw::read_file(dir_.file("echo.out")) << dw::read_file(dir_.file("echo.err"))
                              << dw::read_file(dir_.file("pub.err"));
        const auto s = nlohmann::json::parse(dw::read_file(dir_.file("summary.json")));
        ASSERT_EQ(s["topics"].size(), static_cast<std::size_t>(dw::dds::topics::kTopicCount));
        for (const auto& t : s["topics"]) {
            EXPECT_EQ(t["intact"], 10) << t.dump();
            EXPECT_EQ(t["corrupt"], 0) << t.dump();
        }
    }

    std::string a_, b_, addr_a_, addr_b_;
    bool created_ = false;
    dw::test::TempDir dir_;
};
}  // namespace

TEST_F(TwoHosts, MulticastDiscoveryAndDeliveryAcrossTheVeth) {
    expect_delivery({"--profile", "lab", "--insecure", "--transport", "udp"});
}

TEST_F(TwoHosts, UnicastInitialPeerOnly) {
    // No multicast route: discovery can only go by the initial peers each host names.
    ASSERT_EQ(sh("ip -n " + a_ + " route del 224.0.0.0/4"), 0);
    ASSERT_EQ(sh("ip -n " + b_ + " route del 224.0.0.0/4"), 0);
    expect_delivery({"--profile", "lab", "--insecure", "--transport", "udp", "--peer", addr_a_, "--peer", addr_b_});
}

TEST_F(TwoHosts, DiscoveryServerOnHostA) {
    dw::Subprocess server({in(a_, {"fast-discovery-server", "-i", "0", "-l", addr_a_, "-p", "11811"}),
                           dir_.file("server.out"),
                           dir_.file("server.err"),
                           {}});
    expect_delivery({"--profile", "lab", "--insecure", "--transport", "udp", "--discovery-server", addr_a_ + ":11811"});
    server.stop();
}
