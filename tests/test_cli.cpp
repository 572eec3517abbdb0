// Bad input to the lab's executables: one clear line on stderr and exit code 2, never a crash.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "support.hpp"

using dw::test::bin;
using dw::test::expect_one_line_exit_2;
using dw::test::lines;
using dw::test::run;
using dw::test::TempDir;

namespace {
void write(const std::string& path, const std::string& text) { std::ofstream(path) << text; }
}  // namespace

TEST(Cli, UnknownTransport) {
    TempDir d;
    expect_one_line_exit_2(run({bin("dw-probe"), "--transport", "carrier-pigeon", "list"}, d),
                           "dw-probe: error: unknown transport 'carrier-pigeon' (expected default, shm or udp)");
    expect_one_line_exit_2(run({bin("dw-lab"), "loopback", "--transport", "tcp"}, d), "unknown transport 'tcp'");
}

TEST(Cli, DomainOutOfRange) {
    TempDir d;
    expect_one_line_exit_2(run({bin("dw-probe"), "--domain", "233", "list"}, d), "--domain: 233 is not in [0, 232]");
    expect_one_line_exit_2(run({bin("dw-probe"), "--domain", "-4", "list"}, d), "is not in [0, 232]");
}

TEST(Cli, UnreadableConfig) {
    TempDir d;
    expect_one_line_exit_2(run({bin("dw-probe"), "--config", d.file("missing.yaml"), "list"}, d),
                           "missing.yaml: no such file");
}

TEST(Cli, MalformedConfigNamesFileAndLine) {
    TempDir d;
    write(d.file("bad.yaml"), "dds:\n  domain: 3\n  initial_peers: [127.0.0.1\n");
    expect_one_line_exit_2(run({bin("dw-probe"), "--config", d.file("bad.yaml"), "list"}, d), "bad.yaml:");
    write(d.file("type.yaml"), "dds:\n  domain: three\n");
    expect_one_line_exit_2(run({bin("dw-lab"), "--config", d.file("type.yaml"), "loopback"}, d),
                           "type.yaml:2:11: dds.domain: expected an integer, got 'three'");
    write(d.file("transport.yaml"), "dds:\n  transport: carrier-pigeon\n");
    expect_one_line_exit_2(run({bin("dw-probe"), "--config", d.file("transport.yaml"), "list"}, d),
                           "transport.yaml:2:14: dds.transport: unknown transport 'carrier-pigeon'");
}

TEST(Cli, UsageErrors) {
    TempDir d;
    expect_one_line_exit_2(run({bin("dw-probe"), "list", "--frobnicate"}, d), "--frobnicate");
    expect_one_line_exit_2(run({bin("dw-probe")}, d), "subcommand");
    expect_one_line_exit_2(run({bin("dw-probe"), "echo", "stand/nothing"}, d), "unknown topic 'stand/nothing'");
    expect_one_line_exit_2(run({bin("dw-probe"), "--log-level", "loud", "list"}, d), "unknown log level 'loud'");
    expect_one_line_exit_2(run({bin("dw-probe"), "pub", "--reliability", "mostly"}, d), "--reliability");
    expect_one_line_exit_2(run({bin("dw-probe"), "command", "explode"}, d),
                           "command: unknown kind 'explode' (expected start, calibrate");
    expect_one_line_exit_2(run({bin("dw-mocap-bridge"), "--sim", "--sim-fault", "melt:v1:3"}, d),
                           "unknown fault 'melt' (expected stuck or jump)");
    expect_one_line_exit_2(run({bin("dw-mocap-bridge"), "--sim", "--sim-fault", "stuck:v1:nan"}, d),
                           "--sim-fault 'stuck:v1:nan'");
}

TEST(Cli, HelpExitsZeroAndListsTheCommonOptions) {
    TempDir d;
    const auto r = run({bin("dw-probe"), "--help"}, d);
    EXPECT_EQ(r.status, 0);
    for (const char* opt : {"--help", "--domain", "--config", "--log-level", "--transport", "--profile"}) {
        EXPECT_NE(r.out.find(opt), std::string::npos) << opt;
    }
    const auto sub = run({bin("dw-lab"), "loopback", "--help"}, d);
    EXPECT_EQ(sub.status, 0);
    EXPECT_NE(sub.out.find("--count"), std::string::npos) << sub.out;
}

TEST(SimCli, BadInputIsOneLineAndExit2) {
    TempDir d;
    expect_one_line_exit_2(run({bin("dw-sim"), "fly", "--formation", "triangle", "--out", d.file("f")}, d),
                           "unknown formation 'triangle'");
    expect_one_line_exit_2(
        run({bin("dw-sim"), "fly", "--formation", "single", "--out", d.file("f"), "--physics", d.file("none.yaml")}, d),
        "none.yaml: no such file");
    write(d.file("p.yaml"), "effects:\n  clock_ofset: {enabled: true}\n");
    expect_one_line_exit_2(
        run({bin("dw-sim"), "fly", "--formation", "single", "--out", d.file("f"), "--physics", d.file("p.yaml")}, d),
        "p.yaml:2:3: effects.clock_ofset: unknown key 'clock_ofset'");
    expect_one_line_exit_2(
        run({bin("dw-sim"), "fly", "--formation", "single", "--out", d.file("f"), "--altitudes", "0.3,high"}, d),
        "--altitudes: 'high' is not a number");
    expect_one_line_exit_2(run({bin("dw-sim"), "fly", "--formation", "single"}, d), "--out is required");
}

// Issue 70: an input that is a symbolic link loop is bad input — one line naming it, exit 2 — in
// every tool that reads a flight folder, a recording or a collection (dw-explain said the
// filesystem library's "filesystem error: status: ..." and exited 1).
TEST(Cli, AnInputThatIsASymbolicLinkLoopIsOneLineAndExit2) {
    TempDir d;
    std::filesystem::create_symlink(d.file("b"), d.file("a"));
    std::filesystem::create_symlink(d.file("a"), d.file("b"));
    const std::string loop = d.file("a");
    const std::vector<std::vector<std::string>> commands{
        {bin("dw-explain"), "--real", loop, "--out", d.file("o1")},
        {bin("dw-explain"), "--quiet", "calibrate", "--flights", loop, "--out", d.file("o2")},
        {bin("dw-sim"), "replay", "--flight", loop, "--out", d.file("o3")},
        {bin("dw-recorder"), "export", loop, "--flight", d.file("o4")},
        {bin("dw-import"), "neural-swarm-collection", loop, "--out", d.file("o5")},
    };
    for (const auto& c : commands) {
        SCOPED_TRACE(c[0] + " " + c[1]);
        expect_one_line_exit_2(run(c, d), "Too many levels of symbolic links");
    }
}

// dw-sim replay: a flight's wrench as the physics predicts it along its poses; the RMS against the
// recording on its blocks printed; a discrepancy this build cannot evaluate is one line and exit 2.
TEST(SimCli, ReplayPrintsHowCloseThePhysicsComesAndRefusesAForeignDiscrepancy) {
    TempDir d;
    ASSERT_EQ(
        run({bin("dw-sim"), "fly", "--formation", "single", "--legs", "6", "--quiet", "--out", d.file("f")}, d).status,
        0);
    const auto r = run({bin("dw-sim"), "replay", "--flight", d.file("f"), "--out", d.file("r")}, d);
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("physics alone:"), std::string::npos) << r.out;
    EXPECT_EQ(r.out.find("with the discrepancy"), std::string::npos) << r.out;
    EXPECT_EQ(dw::read_file(d.file("f/poses.csv")), dw::read_file(d.file("r/poses.csv")));
    EXPECT_NE(dw::read_file(d.file("f/wrench.csv")), dw::read_file(d.file("r/wrench.csv")));
    write(d.file("p.yaml"),
          "discrepancy:\n  - {flight: x, heldout_gain: 0.1, height_lo_m: 0, height_step_m: 0.1, height_width_m: 0.1, "
          "t0_s: 0, t1_s: 1, drift_bumps: 2, push_top: 1, sigma: [1, 1, 1, 1, 1, 1], coefficients: [[1], [1], [1], "
          "[1], [1], [1]]}\n");
    expect_one_line_exit_2(
        run({bin("dw-sim"), "replay", "--flight", d.file("f"), "--physics", d.file("p.yaml"), "--out", d.file("s")}, d),
        "discrepancy: coefficients: 6 rows of 1 inputs");
    expect_one_line_exit_2(run({bin("dw-sim"), "replay", "--flight", d.file("none"), "--out", d.file("s")}, d), "none");
}

TEST(SimCli, SameInputsAndSeedGiveTheSameBytes) {
    TempDir d;
    for (const char* out : {"a", "b"}) {
        const auto r = run({bin("dw-sim"), "fly", "--formation", "stack", "--legs", "4", "--seed", "5", "--quiet",
                            "--out", d.file(out)},
                           d);
        ASSERT_EQ(r.status, 0) << r.err;
        EXPECT_NE(r.out.find("4 legs"), std::string::npos) << r.out;
    }
    for (const char* name : {"meta.json", "wrench.csv", "poses.csv", "legs.csv"}) {
        EXPECT_EQ(dw::read_file(d.file(std::string("a/") + name)), dw::read_file(d.file(std::string("b/") + name)))
            << name;
    }
    const auto r = run(
        {bin("dw-sim"), "fly", "--formation", "stack", "--legs", "4", "--seed", "6", "--quiet", "--out", d.file("c")},
        d);
    ASSERT_EQ(r.status, 0);
    EXPECT_NE(dw::read_file(d.file("a/wrench.csv")), dw::read_file(d.file("c/wrench.csv")));
}

TEST(StandCli, CalibrateFitsKnownLoadsAndRejectsBadFilesClearly) {
    TempDir d;
    const std::string csv = dw::test::known_loads_csv();
    write(d.file("loads.csv"), csv);
    const auto ok =
        run({bin("dw-stand-agent"), "calibrate", "--loads", d.file("loads.csv"), "--out", d.file("cal.yaml")}, d);
    ASSERT_EQ(ok.status, 0) << ok.err;
    EXPECT_NE(ok.out.find("residual"), std::string::npos) << ok.out;
    EXPECT_NE(ok.out.find("condition number"), std::string::npos) << ok.out;
    EXPECT_NE(dw::read_file(d.file("cal.yaml")).find("downwash-stand-calibration/1"), std::string::npos);
    write(d.file("bad.csv"),
          "c0,c1,c2,c3,c4,c5,c6,c7,f_n,f_e,f_d,m_roll,m_pitch,m_yaw\n1,2,3,4,5,6,7,8,9,10,11,12,13,x\n");
    expect_one_line_exit_2(run({bin("dw-stand-agent"), "calibrate", "--loads", d.file("bad.csv")}, d),
                           "bad.csv:2: column 14: 'x' is not a number");
    const auto nogpio = run({bin("dw-stand-agent"), "run", "--domain", "9"}, d);
    EXPECT_EQ(nogpio.status, 1);
    EXPECT_NE(nogpio.err.find("cannot open GPIO chip gpiochip0"), std::string::npos) << nogpio.err;
}

TEST(PlannerCli, PlanPrintsItsFiguresAndRejectsInfeasiblePlansInOneLine) {
    TempDir d;
    const auto ok = run({bin("dw-planner"), "plan", "--formation", "stack", "--out", d.file("p.json")}, d);
    ASSERT_EQ(ok.status, 0) << ok.err;
    EXPECT_NE(ok.out.find("36 legs"), std::string::npos) << ok.out;
    EXPECT_NE(ok.out.find("coverage"), std::string::npos);
    EXPECT_NE(dw::read_file(d.file("p.json")).find("downwash-plan/1"), std::string::npos);
    EXPECT_GT(dw::read_file(d.file("p.png")).size(), 1000u);
    expect_one_line_exit_2(run({bin("dw-planner"), "plan", "--formation", "leader_follower3", "--min-separation", "0.6",
                                "--out", d.file("q.yaml")},
                               d),
                           "infeasible plan: v1 and v2 come 0.5 m apart");
    expect_one_line_exit_2(run({bin("dw-planner"), "plan", "--formation", "single", "--altitudes", "2.0"}, d),
                           "--altitudes: 2 is not in [0.05, 1.4] m");
}
