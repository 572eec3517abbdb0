// dw-import on the shared Neural-Swarm logs (read from ../shared, never copied; skipped with the
// reason when absent): CSV and binary of one flight agree, damaged blocks are skipped and counted,
// bad columns are one located error, every shared trial becomes a valid flight folder.
#include <gtest/gtest.h>

#include <chrono>
#include <random>
#include <stop_token>
#include <thread>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <map>
#include <nlohmann/json.hpp>

#include <sys/resource.h>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/stats.hpp"
#include "flight/flight.hpp"
#include "importer/neural_swarm.hpp"
#include "real_data.hpp"
#include "support.hpp"

using namespace dw::importer;
namespace fs = std::filesystem;

namespace {
const std::string& kData = dw::test::kNeuralSwarm;

std::vector<std::string> trial(const std::vector<std::string>& files) {
    std::vector<std::string> out;
    for (const auto& f : files) out.push_back(kData + f);
    return out;
}

std::string bytes_of(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

std::string error_of(const std::vector<std::string>& logs) {
    try {
        neural_swarm_importer().import(logs, {});
    } catch (const dw::InputError& e) {
        return e.what();
    }
    return "(no error)";
}
}  // namespace

TEST(Import, CsvAndBinaryOfOneFlightAgree) {
    REQUIRE_SHARED_DATA();
    const auto a = neural_swarm_importer().import(trial({"swap_ss/cf50_01.csv", "swap_ss/cf51_01.csv"}), {});
    const auto b = neural_swarm_importer().import(trial({"swap_ss/cf50_01", "swap_ss/cf51_01"}), {});
    ASSERT_EQ(a.wrench.size(), b.wrench.size());
    ASSERT_EQ(a.poses.size(), b.poses.size());
    for (std::size_t i = 0; i < a.wrench.size(); ++i) {
        ASSERT_NEAR(a.wrench[i].t, b.wrench[i].t, 1e-9);
        for (std::size_t k = 0; k < 3; ++k) ASSERT_NEAR(a.wrench[i].w[k], b.wrench[i].w[k], 1e-6) << i;
    }
    for (std::size_t i = 0; i < a.poses.size(); ++i) {
        for (std::size_t k = 0; k < 3; ++k) ASSERT_NEAR(a.poses[i].p[k], b.poses[i].p[k], 1e-6) << i;
        for (std::size_t k = 0; k < 4; ++k)
            ASSERT_NEAR(a.poses[i].q[k], b.poses[i].q[k], 2e-3) << i;  // the CSV's quaternion is the decompressed one
    }
}

TEST(Import, EverySharedTrialIsAValidFlightWithDownwashOnTheLowerVehicle) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    const auto& trials = dw::test::shared_trials();
    for (std::size_t k = 0; k < trials.size(); ++k) {
        const auto f = neural_swarm_importer().import(trials[k].paths(), {trials[k].sufferer, {}, {}});
        const std::string dir = d.file("t" + std::to_string(k));
        dw::flight::write_flight(f, dir);
        const auto back = dw::flight::read_flight(dir);  // through the contract
        EXPECT_FALSE(back.meta.stand_height_m);
        EXPECT_EQ(back.meta.wrench_source, dw::flight::WrenchSource::residual);
        EXPECT_FALSE(back.meta.moments_measured);
        EXPECT_EQ(back.meta.neighbours.size(), trials[k].logs.size() - 1);
        EXPECT_GT(back.wrench.size(), 1500u);
        // Downwash pushes the lower vehicle down (+d) harder than anything while alone: the
        // largest downward residual well above the tared level.
        double max_d = 0, min_d = 0;
        for (const auto& s : back.wrench) max_d = std::max(max_d, s.w[2]), min_d = std::min(min_d, s.w[2]);
        if (k < 4) EXPECT_GT(max_d, 2 * std::abs(min_d)) << trials[k].name;
    }
}

TEST(Import, DamagedBlocksAreSkippedAndCounted) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    const std::string original = bytes_of(kData + "swap_ss/cf50_01");
    std::string bytes = original;
    const std::size_t full = read_neural_swarm_log(kData + "swap_ss/cf50_01").t_s.size();
    bytes[bytes.size() / 2] ^= 0x5a;  // inside one block: its checksum fails
    std::ofstream(d.file("cf50_01"), std::ios::binary) << bytes;
    const auto damaged = read_neural_swarm_log(d.file("cf50_01"));
    EXPECT_EQ(damaged.damaged_blocks, 1u);
    EXPECT_LT(damaged.t_s.size(), full);
    EXPECT_GT(damaged.t_s.size(), full - 10);  // one block of a few records lost, the rest kept
    std::ofstream(d.file("cf51_01"), std::ios::binary) << original.substr(0, original.size() - 50);  // truncated
    EXPECT_EQ(read_neural_swarm_log(d.file("cf51_01")).damaged_blocks, 1u);
    std::string header = bytes;
    header[10] ^= 0x01;
    std::ofstream(d.file("cf52_01"), std::ios::binary) << header;
    EXPECT_NE(error_of({d.file("cf52_01"), d.file("cf50_01")}).find("header checksum mismatch"), std::string::npos);
}

// The column names of a Neural-Swarm CSV's header line ("# a,b,c").
std::vector<std::string> split_csv_header(const std::string& csv) {
    std::vector<std::string> out;
    std::stringstream in(csv.substr(2, csv.find('\n') - 2));
    for (std::string c; std::getline(in, c, ',');) out.push_back(c);
    return out;
}

TEST(Import, BadColumnsAndValuesAreOneLocatedLine) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    std::string csv = bytes_of(kData + "swap_ss/cf50_01.csv");
    std::string renamed = csv;
    renamed.replace(renamed.find("qw"), 2, "qq");
    std::ofstream(d.file("cf50_01.csv")) << renamed;
    EXPECT_NE(error_of({d.file("cf50_01.csv")}).find("column 'qw' is missing"), std::string::npos);
    std::string bad = csv;
    const auto line3 = bad.find('\n', bad.find('\n') + 1) + 1;
    bad.replace(line3, bad.find(',', line3) - line3, "oops");
    std::ofstream(d.file("cf50_01.csv")) << bad;
    EXPECT_NE(error_of({d.file("cf50_01.csv")}).find("cf50_01.csv:3: column time[ms]: 'oops' is not a finite number"),
              std::string::npos)
        << error_of({d.file("cf50_01.csv")});
    // Issue 43: an az of 1e308 was imported (and written into a flight); now one located line. A
    // PWM duty (a fraction) was checked against the raw [0, 65536]: 65536 made a thrust of 3.5e9 N,
    // refused only when the flight was written, naming the output's row.
    const auto header = split_csv_header(csv);
    auto with_line3 = [&](const std::string& column, const std::string& value) {
        std::string text = csv;
        const auto col = static_cast<std::size_t>(std::find(header.begin(), header.end(), column) - header.begin());
        std::size_t at = line3;
        for (std::size_t c = 0; c < col; ++c) at = text.find(',', at) + 1;
        text.replace(at, text.find(',', at) - at, value);
        std::ofstream(d.file("cf50_01.csv")) << text;
        return error_of({d.file("cf50_01.csv")});
    };
    const std::string huge = with_line3("az[m/s^2]", "1e308");
    EXPECT_NE(huge.find("cf50_01.csv:3: column az[m/s^2]: 1e+308 is not in [-1000, 1000]"), std::string::npos) << huge;
    const std::string duty = with_line3("u1[PWM]", "65536");
    EXPECT_NE(duty.find("cf50_01.csv:3: column u1[PWM]: 65536 is not in [0, 1]"), std::string::npos) << duty;
    // One log alone is no longer an error: a vehicle alone (Import.AVehicleAloneIsAFlightWithout...).
    EXPECT_EQ(error_of({kData + "swap_ss/cf50_01.csv"}), "(no error)");
    EXPECT_NE(error_of({d.file("cf99_01.csv")}).find("not one the Neural-Swarm collection describes"),
              std::string::npos);
}

// Issue 41, item 5: meta.json's source names the collection the logs came from (the folder above
// the log's own, as the source keeps them), not one fixed name; logs of two collections are refused.
TEST(Import, MetaNamesTheCollectionTheLogsCameFrom) {
    REQUIRE_SHARED_DATA();
    auto collection = [](const dw::flight::Flight& f) {
        return nlohmann::json::parse(f.meta.extra_json)["source"]["collection"].get<std::string>();
    };
    const auto shared = neural_swarm_importer().import(trial({"swap_ss/cf50_01", "swap_ss/cf51_01"}), {});
    EXPECT_EQ(collection(shared), "aerorobotics/neural-swarm datacollection21_06_16_2020");
    // Issue 71: each vehicle's median battery voltage, a covariate of the trial (a 1S LiPo's range).
    const auto battery = nlohmann::json::parse(shared.meta.extra_json)["battery_v"];
    for (const char* v : {"cf50", "cf51"}) {
        ASSERT_TRUE(battery.contains(v)) << battery.dump();
        EXPECT_GT(battery[v].get<double>(), 3.0) << v;
        EXPECT_LT(battery[v].get<double>(), 4.3) << v;
    }
    dw::test::TempDir d;
    for (const char* dir : {"datacollection_other/swap_ss", "another/swap_ss"}) {
        fs::create_directories(d.file(dir));
        for (const char* log : {"cf50_01", "cf51_01"})
            fs::copy_file(kData + "swap_ss/" + log, d.file(std::string(dir) + "/" + log));
    }
    const auto other = neural_swarm_importer().import(
        {d.file("datacollection_other/swap_ss/cf50_01"), d.file("datacollection_other/swap_ss/cf51_01")}, {});
    EXPECT_EQ(collection(other), "aerorobotics/neural-swarm datacollection_other");
    const std::string e = error_of({d.file("datacollection_other/swap_ss/cf50_01"), d.file("another/swap_ss/cf51_01")});
    EXPECT_NE(e.find("come from two collections"), std::string::npos) << e;
    EXPECT_EQ(e.find('\n'), std::string::npos) << e;
    EXPECT_EQ(collection_of({"/cf50_01"}), "(unknown collection)");
}

// Issue 41: a vehicle flying alone is a flight without neighbours (what its residual does with
// nobody near), its Fa tared over the whole flight.
TEST(Import, AVehicleAloneIsAFlightWithoutNeighboursTaredOverItsWholeFlight) {
    REQUIRE_SHARED_DATA();
    std::vector<std::string> logs;
    for (const auto& t : collection_trials(kData))
        if (t.name == "randomwalk_s_00") logs = t.logs;
    ASSERT_EQ(logs.size(), 1u);
    const auto f = neural_swarm_importer().import(logs, {});
    EXPECT_TRUE(f.meta.neighbours.empty());
    EXPECT_EQ(f.meta.sufferer, "cf50");
    std::vector<double> fd;
    for (const auto& w : f.wrench) fd.push_back(w.w[2]);
    ASSERT_GT(fd.size(), 1000u);
    EXPECT_NEAR(dw::median(fd), 0.0, 1e-9);  // the tare is the median of every sample
}

// Issue 41: a whole collection in one command — every trial found, the binary log preferred, the
// logs named with their experiment (the same names recur across experiments), and the default
// sufferer never the vehicle whose residual the authors say not to use.
TEST(Import, ACollectionIsListedTrialByTrialAndEachTrialKeepsItsExperimentInItsLogs) {
    REQUIRE_SHARED_DATA();
    const auto trials = collection_trials(kData);
    std::map<std::string, std::vector<std::string>> by;
    for (const auto& t : trials) by[t.name] = t.logs;
    ASSERT_TRUE(by.count("swap_ss_01") && by.count("randomwalk_ss_02") && by.count("swap_ss_02"));
    EXPECT_EQ(by["swap_ss_01"], trial({"swap_ss/cf50_01", "swap_ss/cf51_01"})) << "the binary log, not the CSV";
    EXPECT_EQ(by["swap_sl_01"], trial({"swap_sl/cf101_01.csv", "swap_sl/cf51_01.csv"})) << "a CSV where no binary is";
    EXPECT_EQ(by["randomwalk_s_00"].size(), 1u);
    auto logs = [](const dw::flight::Flight& f) { return nlohmann::json::parse(f.meta.extra_json)["source"]["logs"]; };
    const auto swap = neural_swarm_importer().import(by["swap_ss_02"], {});
    const auto walk = neural_swarm_importer().import(by["randomwalk_ss_02"], {});
    EXPECT_EQ(logs(swap)[0], "swap_ss/cf50_02");
    EXPECT_NE(logs(swap), logs(walk));
    const auto lll = neural_swarm_importer().import(by["swap_lll_01"], {});
    EXPECT_NE(lll.meta.sufferer, "cf100");
    dw::test::TempDir d;
    EXPECT_THROW(collection_trials(d.file("none")), dw::InputError);
    EXPECT_THROW(collection_trials(d.file("")), dw::InputError);  // a folder without trials
}

// Issue 41: the authors' onboard network (ctrlFa.Faz) comes along as the flight's reference
// prediction of f_d — from the binary logs, which carry it; it follows the measured downwash.
TEST(Import, TheOnboardNetworksPredictionBecomesTheReference) {
    REQUIRE_SHARED_DATA();
    const auto f = neural_swarm_importer().import(trial({"swap_ss/cf50_01", "swap_ss/cf51_01"}), {});
    ASSERT_TRUE(f.meta.reference.has_value());
    EXPECT_EQ(f.meta.reference->axes, std::vector<std::string>{"f_d"});
    ASSERT_EQ(f.reference.size(), f.wrench.size());
    double sxy = 0, sxx = 0, syy = 0, mx = 0, my = 0;
    for (std::size_t i = 0; i < f.wrench.size(); ++i) mx += f.wrench[i].w[2], my += f.reference[i].w[2];
    mx /= static_cast<double>(f.wrench.size()), my /= static_cast<double>(f.wrench.size());
    for (std::size_t i = 0; i < f.wrench.size(); ++i) {
        const double x = f.wrench[i].w[2] - mx, y = f.reference[i].w[2] - my;
        sxy += x * y, sxx += x * x, syy += y * y;
        EXPECT_TRUE(std::isnan(f.reference[i].w[0]));
    }
    EXPECT_GT(sxy / std::sqrt(sxx * syy), 0.6) << "the network predicts the downwash the residual measures";
    const auto csv = neural_swarm_importer().import(trial({"swap_ss/cf50_01.csv", "swap_ss/cf51_01.csv"}), {});
    EXPECT_FALSE(csv.meta.reference.has_value()) << "the CSVs do not carry it";
    dw::test::TempDir d;
    dw::flight::write_flight(f, d.file("f"));
    EXPECT_EQ(dw::flight::read_flight(d.file("f")).reference.size(), f.reference.size());
}

// Issue 70: a log with a garbage tail is resynchronised offset by offset, each try a checksum over
// the block it claims; over 10 MB that ran on past SIGINT. The reader now honours a stop as it scans.
TEST(Import, AStopEndsTheScanThroughAGarbageTail) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    std::string bytes = bytes_of(kData + "swap_ss/cf50_01");
    std::mt19937_64 rng(70);
    for (std::size_t i = 0; i < (10u << 20); ++i) bytes.push_back(static_cast<char>(rng() & 0xff));
    std::ofstream(d.file("cf50_01"), std::ios::binary) << bytes;
    // Unstopped, this tail takes about 34 s on 2 cores (one scan, offset by offset): a stop a second
    // in lands inside it.
    std::stop_source stop;
    std::jthread stopper([&] {
        std::this_thread::sleep_for(std::chrono::seconds(1));
        stop.request_stop();
    });
    EXPECT_THROW(read_neural_swarm_log(d.file("cf50_01"), stop.get_token()), dw::Stopped);
}

namespace {
// A CSV log of `samples` rows of a vehicle hovering at 1 m (every column the importer reads).
void write_hover_log(const std::string& path, std::size_t samples) {
    std::ofstream out(path);
    out << "# time[ms],x[m],y[m],z[m],ax[m/s^2],ay[m/s^2],az[m/s^2],qx,qy,qz,qw,u1[PWM],u2[PWM],u3[PWM],u4[PWM],"
           "Vbat[V],vx[m/s],vz[m/s]\n";
    for (std::size_t i = 0; i < samples; ++i) out << i * 10000 << ",0,0,1,0,0,9.8,0,0,0,1,0.5,0.5,0.5,0.5,4,0,0\n";
}

double children_peak_mb() {
    rusage u{};
    ::getrusage(RUSAGE_CHILDREN, &u);
    return static_cast<double>(u.ru_maxrss) / 1024.0;
}
// docs/HOSTILE_INPUT.md's figure for an import at kMaxTrialSamples (measured: 363 MB).
constexpr double kImportPeakMb = 512;
}  // namespace

// Issue 70: a 10-million-row log peaked at 3.9 GB. A trial is now capped at kMaxTrialSamples: the
// next sample is refused naming its line, whatever follows it, and a trial at the cap imports
// within the documented peak.
TEST(Import, ATrialPastItsCapIsRefusedAtItsLineAndMemoryStaysUnderItsFigure) {
    using dw::test::bin;
    dw::test::TempDir d;
    fs::create_directories(d.file("c/e"));
    write_hover_log(d.file("c/e/cf50_01.csv"), kMaxTrialSamples + 1);
    const auto past =
        dw::test::run({bin("dw-import"), "neural-swarm", d.file("c/e/cf50_01.csv"), "--out", d.file("o1")}, d);
    dw::test::expect_one_line_exit_2(past, dw::log::cat("cf50_01.csv:", kMaxTrialSamples + 2, ": more than ",
                                                        kMaxTrialSamples, " samples in one trial"));
    EXPECT_FALSE(fs::exists(d.file("o1")));
    write_hover_log(d.file("c/e/cf50_01.csv"), kMaxTrialSamples);
    const auto at =
        dw::test::run({bin("dw-import"), "neural-swarm", d.file("c/e/cf50_01.csv"), "--out", d.file("o2")}, d);
    EXPECT_EQ(at.status, 0) << at.err;
    EXPECT_EQ(dw::flight::read_flight(d.file("o2")).wrench.size(), kMaxTrialSamples);
    EXPECT_LT(children_peak_mb(), kImportPeakMb);
    // Two logs share the cap: the second is refused where the trial's budget ends.
    write_hover_log(d.file("c/e/cf51_01.csv"), 2);
    const auto two = dw::test::run(
        {bin("dw-import"), "neural-swarm", d.file("c/e/cf50_01.csv"), d.file("c/e/cf51_01.csv"), "--out", d.file("o3")},
        d);
    dw::test::expect_one_line_exit_2(two, "cf51_01.csv:2: more than");
    // A CSV log's line is held whole: one endless line is refused at its start, not read into memory.
    std::ofstream(d.file("c/e/cf51_01.csv")) << "# " << std::string(1 << 20, 'x');
    const auto endless =
        dw::test::run({bin("dw-import"), "neural-swarm", d.file("c/e/cf51_01.csv"), "--out", d.file("o5")}, d);
    dw::test::expect_one_line_exit_2(endless, "cf51_01.csv:1: a line longer than");
    // A binary log is read whole: past kMaxBinaryLogBytes it is refused before it is read.
    { std::ofstream(d.file("c/e/cf52_01")); }
    fs::resize_file(d.file("c/e/cf52_01"), kMaxBinaryLogBytes + 1);
    const auto binary =
        dw::test::run({bin("dw-import"), "neural-swarm", d.file("c/e/cf52_01"), "--out", d.file("o4")}, d);
    dw::test::expect_one_line_exit_2(binary, "more than a binary log may hold");
}
