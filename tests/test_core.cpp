// Unit tests of the core library's pieces that other tests do not reach on their own.
#include <random>
#include <regex>
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "core/cli.hpp"
#include "core/command.hpp"
#include "core/files.hpp"
#include "core/bounded_map.hpp"
#include "core/errors.hpp"
#include "core/parallel.hpp"
#include "core/stats.hpp"

using dw::Cores;

namespace {
void until(const std::function<bool()>& done) {  // no time limit: CTest's timeout is the limit
    while (!done()) std::this_thread::yield();
}
}  // namespace

TEST(Cores, FillInWorkWaitsForAFreeCoreFirstComeFirst) {
    Cores cores(1);
    std::optional<Cores::Pass> first(cores.take(Cores::Turn::now, {}, "first"));
    std::mutex m;
    std::vector<int> order;
    auto fill_in = [&](int id) {
        const auto pass = cores.take(Cores::Turn::when_free, {}, "filling in");
        const std::lock_guard lock(m);
        order.push_back(id);
    };
    std::jthread a(fill_in, 1);
    until([&] { return cores.waiting() == 1; });
    std::jthread b(fill_in, 2);
    until([&] { return cores.waiting() == 2; });
    {
        const auto beyond = cores.take(Cores::Turn::now, {}, "more");  // never waits, counts
        EXPECT_EQ(cores.busy(), 2);
    }
    EXPECT_EQ(cores.busy(), 1);
    EXPECT_EQ(cores.waiting(), 2);
    first.reset();
    a.join();
    b.join();
    EXPECT_EQ(order, (std::vector<int>{1, 2}));
    EXPECT_EQ(cores.busy(), 0);
}

TEST(Cores, FillInWorkGoesAtOnceWhileACoreIsFree) {
    Cores cores(2);
    const auto one = cores.take(Cores::Turn::now, {}, "one");
    const auto two = cores.take(Cores::Turn::when_free, {}, "two");
    EXPECT_EQ(cores.busy(), 2);
    EXPECT_EQ(cores.waiting(), 0);
}

TEST(Cores, AStopWhileWaitingIsStoppedAndTakesNoCore) {
    Cores cores(1);
    const auto held = cores.take(Cores::Turn::now, {}, "held");
    std::stop_source stop;
    std::string error;
    std::jthread waiter([&] {
        try {
            const auto pass = cores.take(Cores::Turn::when_free, stop.get_token(), "the wait");
        } catch (const dw::Stopped& e) {
            error = e.what();
        }
    });
    until([&] { return cores.waiting() == 1; });
    stop.request_stop();
    waiter.join();
    EXPECT_EQ(error, "stopped during the wait");
    EXPECT_EQ(cores.busy(), 1);
    EXPECT_EQ(cores.waiting(), 0);
}

// The pieces that carry a paired test's evidence: n equal pieces count n, one dominant piece about
// one (the self-normalised sum never exceeds the square root of the count, whatever the signs: the
// explainer's "not identifiable from this flight" rests on it).
TEST(Stats, EffectiveCountCountsThePiecesThatCarryTheEvidence) {
    EXPECT_DOUBLE_EQ(dw::effective_count(std::vector<double>{2, 2, 2, 2}), 4.0);
    EXPECT_DOUBLE_EQ(dw::effective_count(std::vector<double>{}), 0.0);
    const std::vector<double> one_big{100, 0.1, -0.2, 0.1, 0.3, -0.1, 0.2};
    EXPECT_LT(dw::effective_count(one_big), 1.05);
    const std::vector<double> swap{3.55,  61.77, -0.28, -1.80, 0.16,  2.86,   102.75, -0.44,  -0.21, -4.13,
                                   88.98, -2.02, -6.38, 96.41, -0.67, -19.96, 28.52,  -15.71, 48.99, -0.26};
    EXPECT_NEAR(dw::effective_count(swap), 6.64, 0.01);  // the swap's concealed force scale (docs/REAL.md)
    EXPECT_LT(dw::paired_z(swap), std::sqrt(dw::effective_count(swap)));
}

// Student's t: the tail from the incomplete beta function, and its inverse, against published
// tables (two-sided 5 % and 0.1 %) and the t975 table the jackknife intervals use.
TEST(Stats, StudentTQuantilesMatchTheTables) {
    EXPECT_NEAR(dw::t_two_sided(0.05, 1), 12.706, 1e-3);
    EXPECT_NEAR(dw::t_two_sided(0.05, 9), 2.262, 1e-3);
    EXPECT_NEAR(dw::t_two_sided(0.001, 9), 4.781, 1e-3);
    EXPECT_NEAR(dw::t_two_sided(0.05, 30), 2.042, 1e-3);
    for (int dof = 1; dof <= 10; ++dof) EXPECT_NEAR(dw::t_two_sided(0.05, dof), dw::t975(dof), 1e-3) << dof;
    EXPECT_NEAR(dw::t_tail_two_sided(2.262, 9), 0.05, 1e-4);
    EXPECT_NEAR(dw::t_tail_two_sided(0, 5), 1.0, 1e-12);
    EXPECT_NEAR(dw::normal_upper(0.025), 1.95996, 1e-4);
    EXPECT_NEAR(dw::normal_upper(0.001), 3.09023, 1e-4);
    EXPECT_NEAR(dw::normal_upper(0.5), 0.0, 1e-9);
}

// The chi-square upper quantiles a session's one-value test uses, against published tables (1 %).
TEST(Stats, ChiSquareQuantilesMatchTheTables) {
    EXPECT_NEAR(dw::chi2_upper(0.01, 2), 9.210, 0.1);
    EXPECT_NEAR(dw::chi2_upper(0.01, 4), 13.277, 0.1);
    EXPECT_NEAR(dw::chi2_upper(0.01, 9), 21.666, 0.1);
    EXPECT_NEAR(dw::chi2_upper(0.05, 19), 30.144, 0.1);
    EXPECT_EQ(dw::chi2_upper(0.01, 0), 0.0);
}

// A session's flights pooled as random effects. With equal errors v Paule-Mandel's spread has a
// closed form, tau² = s² − v (s²: the values' sample variance), and the mean is the plain mean;
// a known spread wider than the scatter is kept as it is; values that agree add no spread.
TEST(Stats, RandomEffectsPoolWithPauleMandelsSpreadAndHartungKnappsInterval) {
    const std::vector<std::pair<double, double>> scattered{{0.9, 0.01}, {1.3, 0.01}, {1.0, 0.01}, {1.5, 0.01}};
    const auto r = dw::random_effects(scattered, 0.0);
    const double mean = (0.9 + 1.3 + 1.0 + 1.5) / 4;
    double s2 = 0;
    for (const auto& [x, v] : scattered) s2 += (x - mean) * (x - mean) / 3;
    EXPECT_NEAR(r.mean, mean, 1e-9);
    EXPECT_NEAR(r.between_sd * r.between_sd, s2 - 0.01, 1e-9);
    EXPECT_NEAR(r.se, std::sqrt(s2 / 4), 1e-9);
    EXPECT_NEAR(r.half95, dw::t975(3) * r.se, 1e-12);
    EXPECT_EQ(r.dof, 3);
    EXPECT_NEAR(r.q, 3 * s2 / 0.01, 1e-9) << "Cochran's Q with no spread known";
    const auto known = dw::random_effects(scattered, 0.5);
    EXPECT_DOUBLE_EQ(known.between_sd, 0.5) << "a known spread wider than the scatter leaves nothing beyond it";
    EXPECT_LT(known.q, known.dof);
    const std::vector<std::pair<double, double>> agreeing{{2.0, 0.04}, {2.0, 0.01}};
    const auto a = dw::random_effects(agreeing, 0.0);
    EXPECT_EQ(a.between_sd, 0.0);
    EXPECT_NEAR(a.se, 1 / std::sqrt(1 / 0.04 + 1 / 0.01), 1e-12);
    const std::vector<std::pair<double, double>> one{{2.0, 0.04}};
    EXPECT_EQ(dw::random_effects(one, 0.0).dof, 0);
    EXPECT_TRUE(std::isinf(dw::random_effects(one, 0.0).half95));
}

// The robust summaries the explainer, the calibration and the importer share (one rule each).
TEST(Stats, MedianAndTheNoiseOfSuccessiveDifferences) {
    EXPECT_DOUBLE_EQ(dw::median({3, 1, 2}), 2.0);
    EXPECT_DOUBLE_EQ(dw::median({4, 1, 3, 2}), 2.5);  // an even count: the middle pair's mean
    EXPECT_DOUBLE_EQ(dw::median({}), 0.0);
    // White noise of sd 0.5 on a slow ramp, with a few spikes: the ramp and the spikes do not count.
    std::mt19937 rng(7);
    std::normal_distribution<double> noise(0.0, 0.5);
    std::vector<double> x;
    for (int i = 0; i < 20000; ++i) x.push_back(1e-4 * i + noise(rng) + (i % 1000 == 0 ? 50.0 : 0.0));
    EXPECT_NEAR(dw::sd_from_differences(x), 0.5, 0.02);
    EXPECT_DOUBLE_EQ(dw::sd_from_differences(std::vector<double>{1.0}), 0.0);
}

TEST(Stats, HuberCostIsQuadraticInsideAndLinearOutside) {
    EXPECT_DOUBLE_EQ(dw::huber_cost(4.0, 3.0), 4.0);             // |r| = 2 < 3
    EXPECT_DOUBLE_EQ(dw::huber_cost(25.0, 3.0), 2 * 3 * 5 - 9);  // |r| = 5 > 3
    EXPECT_DOUBLE_EQ(dw::huber_cost(9.0, 3.0), 9.0);             // continuous at the edge
    EXPECT_DOUBLE_EQ(dw::ar1_independent_fraction(0.0), 1.0);
    EXPECT_NEAR(dw::ar1_independent_fraction(0.9), 0.1 / 1.9, 1e-12);
}

// A map whose keys come from the network holds at most its capacity; the least recently used key
// is the one forgotten.
TEST(BoundedMap, HoldsItsCapacityAndForgetsTheLeastRecentlyUsed) {
    dw::BoundedMap<int, int> m(3);
    m[1] = 10, m[2] = 20, m[3] = 30;
    m[1] += 1;  // 1 used again: 2 is now the least recent
    m[4] = 40;  // makes room: 2 forgotten
    EXPECT_EQ(m.size(), 3u);
    EXPECT_EQ(m.find(2), nullptr);
    ASSERT_NE(m.find(1), nullptr);
    EXPECT_EQ(*m.find(1), 11);
    EXPECT_EQ(m.forgotten(), 1u);
    for (int k = 100; k < 10000; ++k) m[k] = k;
    EXPECT_EQ(m.size(), 3u);
    EXPECT_EQ(m.forgotten(), 1u + 9900u);
}

// Issue 70: the stamps of a stream held to themselves. A lone stamp far off is refused and moves
// nothing; a frame the network reordered passes; a stream whose clock moved for good is followed
// after kStampsToFollow agreeing stamps; strays interleaved with the stream are never followed.
TEST(StampGate, ALoneStrayIsRefusedAndAStreamThatMovedIsFollowed) {
    const dw::Nanos s = 1'000'000'000, ms = s / 1000;
    dw::StampGate g;
    EXPECT_TRUE(g.accept(100 * s));
    EXPECT_TRUE(g.accept(100 * s + 5 * ms));
    EXPECT_FALSE(g.accept(1'000'000 * s));    // garbled: a million seconds on
    EXPECT_TRUE(g.accept(100 * s + 3 * ms));  // reordered by the network
    EXPECT_TRUE(g.accept(100 * s + 11 * ms));
    for (int i = 0; i < 20; ++i) {  // a forger interleaved with the stream
        EXPECT_FALSE(g.accept(-50 * s + i * ms)) << i;
        EXPECT_TRUE(g.accept(100 * s + (12 + i) * ms)) << i;
    }
    for (int i = 0; i < dw::kStampsToFollow - 1; ++i) EXPECT_FALSE(g.accept(5 * s + i * 6 * ms)) << i;
    EXPECT_TRUE(g.accept(5 * s + (dw::kStampsToFollow - 1) * 6 * ms));  // Motive restarted: followed
    EXPECT_TRUE(g.accept(5 * s + dw::kStampsToFollow * 6 * ms));
    EXPECT_FALSE(g.accept(100 * s));  // the old time is now the stray
    EXPECT_EQ(g.strays(), 1u + 20u + (dw::kStampsToFollow - 1) + 1u);
}

// Issue 73: one command pattern. A tool is its commands: the one the line chose runs (a
// subcommand given, else the main command), with its own options bound; and every tool's main.cpp
// is written that way.
namespace {
struct Counting final : dw::cli::Command {
    explicit Counting(const char* n) : name(n) {}
    const char* name;  // nullptr: the main command, on the app itself
    int value = 0, runs = 0;
    CLI::App* add(CLI::App& app) override {
        CLI::App* where = name ? app.add_subcommand(name, "a command") : &app;
        where->add_option(name ? "--value" : "--main-value", value, "a number")->check(dw::cli::in({0, 100}));
        return where;
    }
    int run() override { return ++runs, value; }
};
int run_line(std::vector<dw::cli::Command*> commands, std::vector<std::string> line) {
    CLI::App app{"a tool"};
    std::vector<char*> argv{const_cast<char*>("tool")};
    for (auto& w : line) argv.push_back(w.data());
    return dw::cli::run_commands(app, commands,
                                 [&] { dw::cli::parse(app, static_cast<int>(argv.size()), argv.data()); });
}
}  // namespace

TEST(Commands, TheChosenCommandRunsElseTheMainOne) {
    Counting main(nullptr), a("a"), b("b");
    EXPECT_EQ(run_line({&main, &a, &b}, {"b", "--value", "7"}), 7);
    EXPECT_EQ(b.runs, 1);
    EXPECT_EQ(a.runs + main.runs, 0);
    EXPECT_EQ(run_line({&main, &a, &b}, {"--main-value", "3"}), 3);
    EXPECT_EQ(main.runs, 1);
    EXPECT_EQ(a.runs, 0);
    Counting c("c"), d("d");
    EXPECT_THROW(run_line({&c, &d}, {}), std::logic_error) << "no command chosen and no main command";
    EXPECT_THROW(run_line({&c, &d}, {"d", "--value", "500"}), dw::InputError) << "its options are checked";
    EXPECT_EQ(d.runs, 0);
}

TEST(Commands, EveryToolsMainIsItsCommands) {
    namespace fs = std::filesystem;
    int tools = 0;
    for (const auto& top : fs::directory_iterator(DW_SOURCE_DIR)) {
        const fs::path main = top.path() / "main.cpp";
        if (!top.is_directory() || !fs::exists(main)) continue;
        ++tools;
        const std::string text = dw::read_file(main.string());
        EXPECT_NE(text.find("dw::cli::run_commands("), std::string::npos) << main << " does not run its commands";
        EXPECT_FALSE(std::regex_search(text, std::regex(R"(\w+\.\w+->parsed\(\)|got_subcommand)")))
            << main << " chooses among its commands itself";
    }
    EXPECT_GE(tools, 11);
}
