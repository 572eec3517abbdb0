// The stand agent against the emulated HX711 bank (virtual time): the chip protocol, gain by
// pulse count, line operations per sample, every fault injected and detected, the tare, known
// loads, and the calibration fit.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numeric>

#include "core/errors.hpp"
#include "physics/stand.hpp"
#include "stand_agent/agent.hpp"
#include "stand_agent/calibration.hpp"
#include "stand_agent/emulated_bank.hpp"
#include "stand_agent/gpiod_lines.hpp"
#include "stand_agent/hx711.hpp"
#include "stand_agent/runner.hpp"
#include "dds/endpoint.hpp"
#include "dds/time.hpp"
#include <thread>
#include <tuple>
#include "support.hpp"

using namespace dw::stand;
using dw::physics::Wrench;

namespace {
struct Rig {
    dw::ManualClock clock;
    std::array<double, kChips> force{};  // N on each cell, set by the test
    BankOptions bank_options;
    std::unique_ptr<EmulatedBank> bank;
    std::unique_ptr<Hx711Driver> driver;
    std::unique_ptr<StandAgent> agent;
    int next_force_glitch = -1;

    explicit Rig(double noise_n = 0.0, DriverOptions dopt = {}, bool shared = true) {
        bank_options.noise_counts = noise_n * bank_options.counts_per_newton;
        bank_options.shared_clock = shared;
        bank = std::make_unique<EmulatedBank>(clock, bank_options, [this](int c, dw::Nanos) {
            if (c == next_force_glitch) {
                next_force_glitch = -1;
                return 50.0;  // a one-conversion glitch, far from the truth
            }
            return force[static_cast<std::size_t>(c)];
        });
        driver = std::make_unique<Hx711Driver>(*bank, dopt);
        AgentOptions a;
        a.calibration = Calibration::nominal(dw::physics::StandParams{});
        agent = std::make_unique<StandAgent>(a, clock);
    }
    StandAgent::Output step() { return agent->process(driver->read_parallel()); }
    void apply(const Wrench& w) {
        const auto cells = dw::physics::StandModel(dw::physics::StandParams{}).wrench_to_cells(w);
        for (int c = 0; c < kChips; ++c) force[static_cast<std::size_t>(c)] = cells[c];
    }
    Wrench wrench_of(const StandAgent::Output& o) {
        Wrench w;
        w << o.wrench.force_n().x(), o.wrench.force_n().y(), o.wrench.force_n().z(), o.wrench.torque_nm().x(),
            o.wrench.torque_nm().y(), o.wrench.torque_nm().z();
        return w;
    }
    void tare() {
        agent->request_tare();
        for (int i = 0; i < 80; ++i) step();
        ASSERT_TRUE(agent->tared());
    }
};
}  // namespace

TEST(Hx711, SignExtends24Bits) {
    EXPECT_EQ(sign_extend_24(0x000001), 1);
    EXPECT_EQ(sign_extend_24(0x7FFFFF), 8388607);
    EXPECT_EQ(sign_extend_24(0x800000), -8388608);
    EXPECT_EQ(sign_extend_24(0xFFFFFF), -1);
}

TEST(Hx711, ReadsEveryChipsConversionMsbFirstTwosComplement) {
    Rig rig;
    for (int c = 0; c < kChips; ++c) rig.force[static_cast<std::size_t>(c)] = -30.0 + 9.0 * c;  // negatives too
    rig.driver->read_parallel();  // the first conversion may predate the forces
    const Hx711Sample s = rig.driver->read_parallel();
    ASSERT_TRUE(s.ok());
    for (int c = 0; c < kChips; ++c) {
        const double expect = std::round(rig.bank->offset(c) + rig.force[static_cast<std::size_t>(c)] * 21400.0);
        EXPECT_EQ(s.counts[static_cast<std::size_t>(c)], static_cast<std::int32_t>(expect)) << c;
    }
}

TEST(Hx711, PulseCountChoosesChannelAndGainOfTheNextConversion) {
    for (auto [gain, expect_gain, scale] :
         {std::tuple{Gain::a64, 64, 0.5}, std::tuple{Gain::b32, 32, 0.0}, std::tuple{Gain::a128, 128, 1.0}}) {
        DriverOptions d;
        d.gain = gain;
        Rig rig(0.0, d);
        rig.force.fill(10.0);
        rig.driver->read_parallel();  // sets the gain for the next conversion
        const Hx711Sample s = rig.driver->read_parallel();
        ASSERT_TRUE(s.ok());
        EXPECT_EQ(rig.bank->gain(0), expect_gain);
        EXPECT_EQ(s.counts[0], static_cast<std::int32_t>(std::round(rig.bank->offset(0) + 10.0 * 21400.0 * scale)));
    }
}

TEST(Hx711, ParallelReadTakesAtMost80LineOperationsOneByOneTakesEightTimesMore) {
    Rig rig;
    rig.driver->read_parallel();
    rig.clock.advance(std::chrono::milliseconds(20));  // every chip has a fresh conversion waiting
    const Hx711Sample s = rig.driver->read_parallel();
    ASSERT_TRUE(s.ok());
    EXPECT_LE(s.ops, 80u);
    EXPECT_EQ(s.ops, 1u + 24u * 3u + 1u * 2u + 1u);  // ready poll, 24 x (high, read, low), 25th pulse, DOUT check
    Rig separate(0.0, {}, false);
    separate.driver->read_one_by_one();
    separate.clock.advance(std::chrono::milliseconds(20));
    const Hx711Sample b = separate.driver->read_one_by_one();
    EXPECT_EQ(b.ops, 8u * s.ops);
}

// A thread pre-empted right after it raised the clock, before it read the time: the clock-high
// phase is timed from before the edge, so the stall still counts (timed from after it, a lab run
// under load published a sample of garbage: 4.7 N on f_n for one sample).
TEST(Faults, APreemptionRightAfterTheClockRisesNeverYieldsAPublishedSample) {
    Rig rig;
    rig.force.fill(1.0);
    for (int i = 0; i < 5; ++i) rig.step();
    rig.clock.advance(std::chrono::milliseconds(20));
    rig.bank->stall_after_next_raise(70'000);
    const Hx711Sample bad = rig.driver->read_parallel();
    EXPECT_TRUE(bad.timing_violation);
    EXPECT_FALSE(rig.agent->process(bad).publish);
}

TEST(Faults, AStretchedPulseNeverYieldsAPublishedSample) {
    Rig rig;
    rig.force.fill(1.0);
    for (int i = 0; i < 5; ++i) rig.step();
    rig.bank->stretch_next_pulse(70'000);  // the thread is pre-empted with the clock high
    const Hx711Sample bad = rig.driver->read_parallel();
    EXPECT_TRUE(bad.timing_violation);
    EXPECT_TRUE(rig.bank->powered_down(0) || bad.timing_violation);
    const auto out = rig.agent->process(bad);
    EXPECT_FALSE(out.publish);
    EXPECT_EQ(rig.agent->status().samples_discarded(), 1u);
    // The chips reset and come back with good data after settling.
    StandAgent::Output next;
    for (int i = 0; i < 10 && !next.publish; ++i) next = rig.step();
    ASSERT_TRUE(next.publish);
    EXPECT_EQ(rig.bank->gain(0), 128);
    EXPECT_EQ(next.frame.counts()[3], static_cast<std::int32_t>(std::round(rig.bank->offset(3) + 21400.0)));
}

TEST(Faults, SpikesNeverReachTheWrench) {
    Rig rig(0.025);
    rig.tare();
    std::uint64_t spikes_before = rig.agent->status().spikes_rejected();
    for (int i = 0; i < 40; ++i) {
        if (i == 10) rig.bank->spike_next(2, true);   // 0x7FFFFF
        if (i == 20) rig.bank->spike_next(5, false);  // 0x800000
        if (i == 30) rig.next_force_glitch = 0;       // a 50 N glitch, not a saturation code
        const auto out = rig.step();
        ASSERT_TRUE(out.publish);
        const Wrench w = rig.wrench_of(out);
        EXPECT_LT(w.head<3>().norm(), 0.3) << "sample " << i;
        EXPECT_LT(w.tail<3>().norm(), 0.05) << "sample " << i;
    }
    EXPECT_GE(rig.agent->status().spikes_rejected() - spikes_before, 3u);
}

TEST(Faults, AnUnpluggedCellPutsTheStandInFaultNamingItWithin100ms) {
    Rig rig;
    for (int i = 0; i < 5; ++i) rig.step();
    rig.bank->unplug(5);
    const dw::Nanos t0 = rig.clock.monotonic_ns();
    bool fault = false;
    for (int i = 0; i < 20 && !fault; ++i) {
        const auto out = rig.step();
        EXPECT_FALSE(out.publish && rig.agent->status().state() == dw::msg::STAND_FAULT);
        fault = rig.agent->status().state() == dw::msg::STAND_FAULT;
    }
    ASSERT_TRUE(fault);
    EXPECT_LE(rig.clock.monotonic_ns() - t0, 100'000'000);  // virtual time: no hang, no wall clock
    const auto st = rig.agent->status();
    ASSERT_EQ(st.fault_cells().size(), 1u);
    EXPECT_EQ(st.fault_cells()[0], 5u);
    EXPECT_NE(st.message().find("cell 5"), std::string::npos) << st.message();
    rig.bank->unplug(5, false);
    StandAgent::Output out;
    for (int i = 0; i < 10 && !out.publish; ++i) out = rig.step();
    EXPECT_TRUE(out.publish);
    EXPECT_EQ(rig.agent->status().state(), dw::msg::STAND_RUNNING);
}

TEST(Faults, AStuckLowLineIsNotMistakenForData) {
    Rig rig;
    rig.force.fill(2.0);
    for (int i = 0; i < 5; ++i) rig.step();
    rig.bank->stick_low(1);
    const auto s = rig.driver->read_parallel();
    // DOUT stuck low looks ready and reads all-zero bits; it does not go high after the 25th pulse.
    EXPECT_EQ(s.stuck, 1u << 1);
    const auto out = rig.agent->process(s);
    EXPECT_FALSE(out.publish);
    EXPECT_EQ(rig.agent->status().state(), dw::msg::STAND_FAULT);
    EXPECT_NE(rig.agent->status().message().find("cell 1 DOUT stuck low"), std::string::npos)
        << rig.agent->status().message();
}

TEST(Tare, WithNoNeighboursTheTaredWrenchIsZeroWithinNoise) {
    Rig rig(0.025);  // per cell: about ±0.05 N on the wrench
    rig.force.fill(0.0);
    rig.tare();
    std::array<double, 6> sum{}, sum2{};
    const int n = 400;
    for (int i = 0; i < n; ++i) {
        const Wrench w = rig.wrench_of(rig.step());
        for (int a = 0; a < 6; ++a) {
            sum[static_cast<std::size_t>(a)] += w[a];
            sum2[static_cast<std::size_t>(a)] += w[a] * w[a];
        }
    }
    for (int a = 0; a < 3; ++a) {
        EXPECT_LT(std::abs(sum[static_cast<std::size_t>(a)] / n), 0.02) << a;
        EXPECT_LT(std::sqrt(sum2[static_cast<std::size_t>(a)] / n), 0.08) << a;
    }
    EXPECT_EQ(rig.agent->status().state(), dw::msg::STAND_RUNNING);
    EXPECT_EQ(rig.agent->status().message(), "tared at hover thrust");
}

TEST(Tare, KnownLoadsComeOutWithin1Percent) {
    Rig rig;
    rig.tare();
    for (const Wrench& load : {Wrench((Wrench() << 0.0, 0.0, 2.0, 0.0, 0.0, 0.0).finished()),
                               Wrench((Wrench() << 0.8, -0.5, 3.0, 0.05, -0.04, 0.01).finished()),
                               Wrench((Wrench() << -1.5, 1.2, -0.7, -0.03, 0.06, -0.02).finished())}) {
        rig.apply(load);
        rig.step();  // conversions already under way saw the old load
        const Wrench w = rig.wrench_of(rig.step());
        for (int a = 0; a < 6; ++a) EXPECT_NEAR(w[a], load[a], 0.01 * std::abs(load[a]) + 2e-4) << "axis " << a;
    }
}

TEST(Calibration, FitRecoversTheStandFromKnownLoadsAndRoundTrips) {
    // A real stand differs from the nominal one: each cell's gain a few percent off.
    const auto nominal = Calibration::nominal(dw::physics::StandParams{});
    const dw::physics::StandModel geometry(dw::physics::StandParams{});
    const std::array<double, kChips> true_gain = {1.03, 0.97, 1.02, 0.99, 1.04, 0.96, 1.01, 0.98};
    std::vector<KnownLoad> loads;
    dw::physics::Rng rng(4);
    for (int i = 0; i < 30; ++i) {
        Wrench w;
        for (int a = 0; a < 6; ++a) w[a] = (a < 3 ? 5.0 : 0.2) * (2 * rng.uniform() - 1);
        const auto cells = geometry.wrench_to_cells(w);
        KnownLoad k;
        for (int c = 0; c < kChips; ++c)
            k.tared_counts[c] = cells[c] * 21400.0 * true_gain[static_cast<std::size_t>(c)];
        k.wrench = w;
        loads.push_back(k);
    }
    const auto fit = fit_calibration(loads, nominal.counts_per_newton);
    EXPECT_LT(fit.residual_rms, 1e-9);
    EXPECT_GT(fit.condition, 1.0);
    EXPECT_LT(fit.condition, 1e3);
    // The fitted stand reads a fresh load within 1 %; the nominal one does not.
    Wrench load;
    load << 0.7, -1.1, 2.5, 0.04, 0.03, -0.01;
    const auto cells = geometry.wrench_to_cells(load);
    CellVector counts;
    for (int c = 0; c < kChips; ++c) counts[c] = cells[c] * 21400.0 * true_gain[static_cast<std::size_t>(c)];
    const Wrench fitted = fit.calibration.wrench(counts), raw = nominal.wrench(counts);
    for (int a = 0; a < 6; ++a) EXPECT_NEAR(fitted[a], load[a], 0.01 * std::abs(load[a])) << a;
    double worst = 0;  // the nominal calibration's worst relative error over the axes
    for (int a = 0; a < 6; ++a) worst = std::max(worst, std::abs(raw[a] - load[a]) / std::abs(load[a]));
    EXPECT_GT(worst, 0.01);
    // Through a file and back.
    dw::test::TempDir d;
    fit.calibration.save(d.file("cal.yaml"));
    const Calibration back = Calibration::load(d.file("cal.yaml"));
    EXPECT_LT((back.cell_to_wrench - fit.calibration.cell_to_wrench).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(Calibration, TooFewOrDegenerateLoadsAreRefusedClearly) {
    const auto nominal = Calibration::nominal(dw::physics::StandParams{});
    std::vector<KnownLoad> vertical_only;
    for (int i = 0; i < 10; ++i) {
        KnownLoad k;
        k.tared_counts.setZero();
        for (int c = 0; c < 4; ++c) k.tared_counts[c] = 21400.0 * (1 + i);
        k.wrench.setZero();
        k.wrench[2] = 4.0 * (1 + i);
        vertical_only.push_back(k);
    }
    try {
        fit_calibration(vertical_only, nominal.counts_per_newton);
        FAIL();
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("do not excite all six axes"), std::string::npos);
    }
    dw::test::TempDir d;
    std::ofstream(d.file("bad.yaml")) << "format: downwash-stand-calibration/1\ncounts_per_newton: [1, 2, 3]\n";
    try {
        Calibration::load(d.file("bad.yaml"));
        FAIL();
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("bad.yaml:2:20: counts_per_newton: expected a list of 8 numbers"),
                  std::string::npos)
            << e.what();
    }
}

// Issue 17: the calibration file is read and written through core/keys, one declaration.
TEST(Calibration, EachMistakeInTheFileIsOneLocatedLine) {
    dw::test::TempDir d;
    const auto error = [&](const std::string& yaml) {
        std::ofstream(d.file("c.yaml")) << yaml;
        try {
            Calibration::load(d.file("c.yaml"));
        } catch (const dw::InputError& e) {
            return std::string(e.what()).substr(d.file("c.yaml").size());
        }
        return std::string("(no error)");
    };
    const std::string gains = "counts_per_newton: [1, 2, 3, 4, 5, 6, 7, 8]\n";
    std::string rows = "cell_to_wrench:\n";
    for (int r = 0; r < 6; ++r) rows += "  - [0, 0, 0, 0, 0, 0, 0, 0]\n";
    const std::string format = "format: downwash-stand-calibration/1\n";
    EXPECT_EQ(error(format + gains + rows), "(no error)");
    EXPECT_EQ(error(gains + rows), ":1:1: format: expected downwash-stand-calibration/1");
    EXPECT_EQ(error(format + "counts_per_newton: [1, 2, 0, 4, 5, 6, 7, 8]\n" + rows),
              ":2:20: counts_per_newton: expected non-zero numbers");
    EXPECT_EQ(error(format + gains),
              ":1:1: cell_to_wrench: expected 6 rows (f_n, f_e, f_d, m_roll, m_pitch, m_yaw) of 8 numbers");
    std::string bad = rows;
    bad.replace(bad.rfind("0]"), 1, "x");
    EXPECT_EQ(error(format + gains + bad), ":9:27: cell_to_wrench[5][7]: expected a number");
    EXPECT_EQ(error(format + gains + rows + "gain: 3\n"),
              ":10:1: gain: unknown key 'gain' (known: cell_to_wrench, counts_per_newton, format)");
}

TEST(Gpio, NoGpioHereFailsCleanly) {
    try {
        GpiodLines lines(GpioPins{});
        GTEST_SKIP() << "this machine has GPIO";
    } catch (const dw::RuntimeError& e) {
        EXPECT_NE(std::string(e.what()).find("cannot open GPIO chip gpiochip0"), std::string::npos) << e.what();
    }
}

namespace {
// A mocap frame of the sufferer at D = suffer_d and v1 at (v1_n, 0, -2), both tracked, stamped at `stamp`.
dw::msg::MocapFrame stand_frame(double suffer_d, double v1_n, dw::Nanos stamp = 0) {
    dw::msg::MocapFrame f;
    f.header().stamp(dw::dds::to_msg(stamp));
    for (auto [name, n, d] : {std::tuple{"sufferer", 0.0, suffer_d}, std::tuple{"v1", v1_n, -2.0}}) {
        dw::msg::RigidBody b;
        b.name(name);
        b.position_m().x(n);
        b.position_m().z(d);
        b.orientation().w(1);
        b.tracking_valid(true);
        f.bodies().push_back(b);
    }
    return f;
}
}  // namespace

// Issue 70: the simulated stand feels the bodies of the motion capture. A body that is no
// measurement (NaN, 1e300 from a wire), the sufferer's own included, is not felt: what the chips
// read stays finite.
TEST(StandPhysicsSource, BodiesThatAreNoMeasurementAreNotFelt) {
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "standsrc" + std::to_string(::getpid());
    dw::dds::Participant stand(cfg, "stand_agent"), bridge(cfg, "mocap_bridge");
    dw::stand::PhysicsSource source(stand, dw::physics::PhysicsConfig{}, dw::SystemClock::instance());
    dw::dds::Writer<dw::msg::MocapFrame> w(bridge, dw::dds::topics::mocap_frame);
    ASSERT_TRUE(w.wait_for_readers(1, std::chrono::seconds(20)));
    const auto frame = [](double suffer_d, double v1_n) { return stand_frame(suffer_d, v1_n); };
    const auto felt = [&] {
        double sum = 0;
        for (int chip = 0; chip < 8; ++chip) sum += source.force(chip, dw::SystemClock::instance().monotonic_ns());
        return sum;
    };
    auto good = frame(-1.4, 0.0);
    w.write(good);
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    ASSERT_TRUE(std::isfinite(felt()));
    for (double garbage : {std::nan(""), 1e300}) {
        auto bad = frame(garbage, garbage);
        w.write(bad);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        EXPECT_TRUE(std::isfinite(felt())) << garbage;
    }
}

// Issue 70: a frame stamped off the frames' own time (a garbled or forged stamp, 1e6 s ahead) is not
// felt (before, its bodies were the stand's air until the next frame, and its stamp the air's lag).
TEST(StandPhysicsSource, AFrameStampedOffTheFramesTimeIsNotFelt) {
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = "standstamp" + std::to_string(::getpid());
    dw::dds::Participant stand(cfg, "stand_agent"), bridge(cfg, "mocap_bridge");
    const auto& clock = dw::SystemClock::instance();
    dw::stand::PhysicsSource source(stand, dw::physics::PhysicsConfig{}, clock);
    dw::dds::Writer<dw::msg::MocapFrame> w(bridge, dw::dds::topics::mocap_frame);
    ASSERT_TRUE(w.wait_for_readers(1, std::chrono::seconds(20)));
    const auto send = [&](double v1_n, double ahead_s) {  // v1 0.6 m above the sufferer, v1_n m north
        auto f = stand_frame(-1.4, v1_n, clock.now_ns() + static_cast<dw::Nanos>(ahead_s * 1e9));
        w.write(f);
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
    };
    const auto felt_z = [&] {  // the cells' sum: the vertical force
        double sum = 0;
        for (int chip = 0; chip < 8; ++chip) sum += source.force(chip, clock.monotonic_ns());
        return sum;
    };
    send(0.0, 0);
    const double overhead = felt_z();
    send(3.0, 1e6);  // v1 gone 3 m north, at a stamp off the frames' time
    EXPECT_NEAR(felt_z(), overhead, 1e-3 * std::abs(overhead) + 1e-6) << "the stray frame was felt";
    EXPECT_EQ(source.stray_stamps(), 1u);
    send(3.0, 0);  // the same, at the frames' time: felt
    EXPECT_GT(std::abs(felt_z() - overhead), 1e-3) << "v1 moving away changed nothing: the test shows nothing";
}
