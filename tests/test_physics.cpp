// The physics pinned to the literature (PHYSICS.md) and each effect's signature.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <numeric>
#include <random>

#include "core/errors.hpp"
#include "flight/blocks.hpp"
#include "physics/config.hpp"
#include "physics/flight_sim.hpp"
#include "physics/jet.hpp"
#include "physics/prediction_noise.hpp"
#include "physics/recording_chain.hpp"
#include "physics/samplers.hpp"
#include "physics/stand.hpp"
#include "physics/wrench_model.hpp"

using namespace dw::physics;

namespace {
PhysicsConfig quiet_config() {
    // No noise anywhere: signatures show without averaging.
    PhysicsConfig c;
    c.turbulence.enabled = false;
    c.stand.noise_n = 0;
    c.dynamics.hover_noise_m = 0;
    c.mocap.noise_m = 0;
    return c;
}

double within(double value, double expected) { return std::abs(value - expected) / std::abs(expected); }

// Where along E the force peak of each direction appears, measured like an analyst would: the
// neighbour's recorded E at each wrench stamp, weighted by f_d above half its maximum.
struct Peaks {
    double plus_e = 0, minus_e = 0;
    double peak_fd = 0;
};
Peaks peak_positions(const dw::flight::Flight& f) {
    const auto tracks = dw::flight::tracks(f);
    const auto& track = tracks[static_cast<std::size_t>(f.find_body(f.meta.neighbours.front()))];
    Peaks p;
    for (const auto& leg : *f.legs) {
        const double mid = 0.5 * (leg.t_start + leg.t_end);
        const int dir = track.position_at(leg.t_end)[1] > track.position_at(leg.t_start)[1] ? 1 : -1;
        double max_fd = 0;
        for (const auto& s : f.wrench) {
            if (std::abs(s.t - mid) < 0.5 * (leg.t_end - leg.t_start)) max_fd = std::max(max_fd, s.w[2]);
        }
        double sw = 0, swe = 0;
        for (const auto& s : f.wrench) {
            if (std::abs(s.t - mid) >= 0.5 * (leg.t_end - leg.t_start) || s.w[2] < 0.5 * max_fd) continue;
            sw += s.w[2];
            swe += s.w[2] * track.position_at(s.t)[1];
        }
        (dir > 0 ? p.plus_e : p.minus_e) = swe / sw;
        p.peak_fd = std::max(p.peak_fd, max_fd);
    }
    return p;
}

// The error parse_physics gives for a YAML text named p.yaml, or "(no error)".
std::string error(const std::string& yaml) {
    try {
        parse_physics(yaml, "p.yaml");
    } catch (const dw::InputError& e) {
        return e.what();
    }
    return "(no error)";
}

FlyOptions over_the_stand(double altitude, const std::string& formation = "single") {
    FlyOptions o;
    o.formation = formation;
    o.grid.altitudes_m = {altitude};
    o.grid.lines_n_m = {0.0, 0.0};  // two legs straight over the stand: +E then -E
    o.grid.legs = 2;
    o.seed = 7;
    return o;
}
}  // namespace

// ---- the jet, pinned to PHYSICS.md (0.7 kg, 5" props, l = 0.25 m, rho 1.225) -------------------

TEST(Jet, BauersfeldNumbersWithin2Percent) {
    const PhysicsConfig c;
    const Jet j = Jet::make(c.neighbour, c);
    EXPECT_LT(within(j.u_hover, 7.4), 0.02) << j.u_hover;
    EXPECT_LT(within(j.centreline(0.3), 10.7), 0.02) << j.centreline(0.3);
    EXPECT_LT(within(j.half_width(0.3), 0.135), 0.02) << j.half_width(0.3);
    EXPECT_LT(within(j.centreline(1.3), 6.8), 0.02) << j.centreline(1.3);
    EXPECT_LT(within(j.half_width(1.3), 0.21), 0.02) << j.half_width(1.3);
    EXPECT_NEAR(j.axial(j.half_width(1.3), 1.3), 0.5 * j.centreline(1.3), 1e-12);  // half-width means half speed
    EXPECT_EQ(j.centreline(-0.1), 0.0);                                            // nothing above the producer
}

TEST(Jet, MomentumFluxIsConstantAndNearThrust) {
    const PhysicsConfig c;
    const Jet j = Jet::make(c.neighbour, c);
    for (double s : {0.5, 1.0, 1.5}) {
        // rho ∫ U² dA, numerically over the plane at depth s.
        double flux = 0;
        const double dr = 1e-4;
        for (double r = 0.5 * dr; r < 20 * j.half_width(s); r += dr) {
            const double u = j.axial(r, s);
            flux += c.air_density_kg_m3 * u * u * 2 * M_PI * r * dr;
        }
        const double thrust = c.neighbour.mass_kg * c.gravity_m_s2;
        EXPECT_LT(within(flux, thrust), 0.10) << "s=" << s << " flux=" << flux;
        EXPECT_LT(within(flux, j.momentum_flux(c.air_density_kg_m3)), 0.01);
        EXPECT_NEAR(flux / thrust, 0.94, 0.01);
    }
}

TEST(Jet, TransportDelayFollowsTheJetLaw) {
    const PhysicsConfig c;
    const Jet j = Jet::make(c.neighbour, c);
    EXPECT_LT(within(j.transport_delay(1.3), 0.146), 0.05) << j.transport_delay(1.3);
    EXPECT_LT(within(j.transport_delay(0.5), 0.045), 0.05) << j.transport_delay(0.5);
    // It is the integral of 1/U_c.
    double tau = 0;
    for (double z = 0.00005; z < 1.3; z += 0.0001) tau += 0.0001 / j.centreline(z);
    EXPECT_NEAR(tau, j.transport_delay(1.3), 1e-4);
}

TEST(Jet, RadialInflowConservesMass) {
    // Continuity: d/ds ∫U dA = -2π r V at the edge of a disc; check at a large radius.
    const PhysicsConfig c;
    const Jet j = Jet::make(c.neighbour, c);
    const double s = 1.0, R = 0.5, ds = 1e-4, dr = 1e-4;
    auto flow = [&](double depth) {
        double q = 0;
        for (double r = 0.5 * dr; r < R; r += dr) q += j.axial(r, depth) * 2 * M_PI * r * dr;
        return q;
    };
    const double dq = (flow(s + ds) - flow(s - ds)) / (2 * ds);
    EXPECT_NEAR(dq, -2 * M_PI * R * j.radial(R, s), 1e-3 * std::abs(dq) + 1e-6);
    EXPECT_LT(j.radial(R, s), 0.0);                      // entrainment: inward outside the core
    EXPECT_GT(j.radial(0.3 * j.half_width(s), s), 0.0);  // outward near the axis
}

// ---- the field and the force ------------------------------------------------------------------

TEST(Field, HoveringProducerIsAxisymmetric) {
    const PhysicsConfig c;
    const WrenchModel m(c);
    const Producer p = m.producer(Vec3(0, 0, -2.7));
    const std::array<Producer, 1> ps{p};
    const Vec3 ref = m.air_velocity(Vec3(0.15, 0, -1.4), ps);
    EXPECT_GT(ref.z(), 1.0);
    for (int k = 1; k < 12; ++k) {
        const double th = 2 * M_PI * k / 12;
        const Vec3 u = m.air_velocity(Vec3(0.15 * std::cos(th), 0.15 * std::sin(th), -1.4), ps);
        EXPECT_NEAR(u.norm(), ref.norm(), 1e-12);
        EXPECT_NEAR(u.z(), ref.z(), 1e-12);
        EXPECT_NEAR(std::hypot(u.x(), u.y()), std::abs(ref.x()), 1e-12);
    }
}

// The model's inner loop computes the profile in a rearranged form (one division per cell, no
// branch, two or four cells at once): it must be the jet's own formulas (Jet::axial, Jet::radial),
// on a tilted, moving producer, with the wake's transport delay and without, above and below it.
TEST(Field, TheFastLoopIsTheJetsOwnFormulas) {
    for (const bool delayed : {false, true}) {
        SCOPED_TRACE(delayed ? "with the transport delay" : "without it");
        PhysicsConfig c;
        constexpr double kDelayScale = 1.3;
        dw::physics::effect_type("wake_transport").store(c.effects, delayed, {kDelayScale}, {});
        const WrenchModel m(c);
        Producer p = m.producer(Vec3(0.1, -0.2, -2.6), Vec3(0.8, -0.3, 0.1));
        p.axis = Vec3(0.12, -0.08, 1.0).normalized();
        const std::array<Producer, 1> ps{p};
        int below = 0;
        for (int k = 0; k < 200; ++k) {
            const Vec3 x(0.9 * std::sin(1.7 * k), 0.9 * std::cos(2.3 * k), -2.6 + 2.4 * std::sin(0.37 * k + 1));
            Vec3 d = x - p.position;
            const double s0 = d.dot(p.axis);
            if (delayed && s0 > 0) d += p.velocity * kDelayScale * p.jet.transport_delay(s0);
            const double s = d.dot(p.axis);
            const Vec3 radial = d - s * p.axis;
            const double r = radial.norm();
            Vec3 expect = Vec3::Zero();
            if (s > 0) {
                expect = p.jet.axial(r, s) * p.axis;
                if (r > 0) expect += p.jet.radial(r, s) * radial / r;
                ++below;
            }
            const Vec3 got = m.air_velocity(x, ps);
            EXPECT_LE((got - expect).norm(), 1e-12 * (1 + expect.norm())) << "at " << x.transpose();
        }
        EXPECT_GT(below, 50);
        EXPECT_LT(below, 190);
    }
}

// The same over the sufferer's whole planform (the loops' two- and four-cell bodies, not only
// their remainder): the wrench the model gives is each cell's drag in the jet's own air, with a
// gust on the jet and without the entrainment term.
TEST(Field, TheWholePlanformsWrenchIsEachCellsDragInTheJetsOwnAir) {
    for (const bool radial : {true, false}) {
        SCOPED_TRACE(radial ? "with entrainment" : "without");
        PhysicsConfig c;
        c.radial_inflow = radial;
        c.sufferer.thrust_loss = false;  // drag alone
        const WrenchModel m(c);
        const auto& cells = m.planform();
        const auto& suf = m.config().sufferer;
        const double rho = m.config().air_density_kg_m3;
        Producer p = m.producer(Vec3(0.12, 0.05, -2.4));
        p.axis = Vec3(-0.1, 0.05, 1.0).normalized();
        p.gust = 1.3;
        const std::array<Producer, 1> ps{p};
        const Vec3 centre(0, 0, -1.4);
        Eigen::Matrix<double, 6, 1> expect = Eigen::Matrix<double, 6, 1>::Zero();
        for (std::size_t i = 0; i < cells.size(); ++i) {
            const Vec3 d = centre + Vec3(cells.x[i], cells.y[i], 0) - p.position;
            const double s = d.dot(p.axis);
            const Vec3 across = d - s * p.axis;
            const double r = across.norm();
            Vec3 u = p.jet.axial(r, s) * p.axis;
            if (radial && r > 0) u += p.jet.radial(r, s) * across / r;
            u *= p.gust;
            const double fz = 0.5 * rho * suf.drag_coefficient * cells.area[i] * std::abs(u.z()) * u.z();
            const double k = 0.5 * rho * suf.lateral_drag_coefficient * cells.area[i] * std::hypot(u.x(), u.y());
            const Vec3 f(k * u.x(), k * u.y(), fz);
            expect.head<3>() += f;
            expect.tail<3>() += Vec3(cells.x[i], cells.y[i], 0).cross(f);
        }
        const auto got = m.evaluate(centre, ps);
        EXPECT_GT(std::abs(expect[2]), 0.05);
        EXPECT_LE((got - expect).norm(), 1e-12 * expect.norm()) << got.transpose() << " vs " << expect.transpose();
    }
}

TEST(Field, TranslatingProducerIsOnlyMirrorSymmetric) {
    PhysicsConfig c;
    dw::physics::effect_type("wake_transport").switch_on(c.effects);
    const WrenchModel m(c);
    const std::array<Producer, 1> ps{m.producer(Vec3(0, 0, -2.7), Vec3(0, 0.5, 0))};  // moving along +E
    double asym = 0;
    for (double n : {0.05, 0.1, 0.2}) {
        for (double e : {-0.2, -0.1, 0.0, 0.1, 0.2}) {
            const Vec3 a = m.air_velocity(Vec3(n, e, -1.4), ps);
            const Vec3 b = m.air_velocity(Vec3(-n, e, -1.4), ps);  // mirrored in the plane of v and vertical
            EXPECT_NEAR(a.x(), -b.x(), 1e-12);
            EXPECT_NEAR(a.y(), b.y(), 1e-12);
            EXPECT_NEAR(a.z(), b.z(), 1e-12);
            const Vec3 fore = m.air_velocity(Vec3(0, e + 0.1, -1.4), ps);
            const Vec3 aft = m.air_velocity(Vec3(0, -(e + 0.1), -1.4), ps);
            asym = std::max(asym, std::abs(fore.z() - aft.z()));
        }
    }
    EXPECT_GT(asym, 0.2);  // not axisymmetric: the wake trails behind
}

TEST(Force, SingleProducerPeakAt03mBetween1And6N) {
    const PhysicsConfig c;
    const WrenchModel m(c);
    const Vec3 suf(0, 0, -1.4);
    double peak = 0;
    for (double n = -0.3; n <= 0.3; n += 0.02) {
        for (double e = -0.3; e <= 0.3; e += 0.02) {
            const std::array<Producer, 1> ps{m.producer(suf + Vec3(n, e, -0.3))};
            peak = std::max(peak, std::abs(m.evaluate(suf, ps)[2]));
        }
    }
    EXPECT_GT(peak, 1.0);
    EXPECT_LT(peak, 6.0);
    // Downwash pushes the sufferer down (+D); far away it is nothing.
    const std::array<Producer, 1> above{m.producer(suf + Vec3(0, 0, -0.3))};
    EXPECT_GT(m.evaluate(suf, above)[2], 0.0);
    const std::array<Producer, 1> far{m.producer(suf + Vec3(0, 3.0, -0.3))};
    EXPECT_LT(std::abs(m.evaluate(suf, far)[2]), 1e-3);
}

TEST(Force, TorqueFollowsTheOffCentreLoad) {
    const PhysicsConfig c;
    const WrenchModel m(c);
    const Vec3 suf(0, 0, -1.4);
    // A producer east of centre loads the east rotors: roll (about N) = Σ y f_d > 0.
    const std::array<Producer, 1> east{m.producer(suf + Vec3(0, 0.1, -0.3))};
    EXPECT_GT(m.evaluate(suf, east)[3], 0.0);
    // North of centre: pitch = -Σ x f_d < 0.
    const std::array<Producer, 1> north{m.producer(suf + Vec3(0.1, 0, -0.3))};
    EXPECT_LT(m.evaluate(suf, north)[4], 0.0);
}

TEST(Force, AggregationLaws) {
    PhysicsConfig c;
    const Vec3 suf(0, 0, -1.4);
    auto two = [&](const WrenchModel& m) {
        const std::array<Producer, 2> ps{m.producer(suf + Vec3(0, -0.1, -0.8)), m.producer(suf + Vec3(0, 0.1, -0.8))};
        return m.evaluate(suf, ps)[2];
    };
    auto one = [&](const WrenchModel& m, double e) {
        const std::array<Producer, 1> ps{m.producer(suf + Vec3(0, e, -0.8))};
        return m.evaluate(suf, ps)[2];
    };
    const WrenchModel sum(c);
    EXPECT_NEAR(two(sum), one(sum, -0.1) + one(sum, 0.1), 1e-9);
    c.aggregation = Aggregation::velocity_superposition;
    const WrenchModel sup(c);
    // Overlapping jets: U² has the cross term 2 u1 u2, so superposed velocities push harder.
    EXPECT_GT(two(sup), 1.2 * (one(sup, -0.1) + one(sup, 0.1)) - 0.3);
    EXPECT_GT(two(sup), two(sum));
}

// ---- the stand ------------------------------------------------------------------------------

TEST(Stand, CellsCarryEveryWrench) {
    const StandModel s(StandParams{});
    Wrench w;
    w << 0.3, -0.2, 1.5, 0.02, -0.03, 0.005;
    const auto cells = s.wrench_to_cells(w);
    EXPECT_LT((s.cells_to_wrench() * cells - w).norm(), 1e-12);
    int vertical = 0, north = 0, east = 0;
    for (const auto& cell : s.cells()) (cell.axis == 2 ? vertical : cell.axis == 0 ? north : east)++;
    EXPECT_EQ(vertical, 4);
    EXPECT_EQ(north, 2);
    EXPECT_EQ(east, 2);
}

TEST(Stand, Hx711CountsSaturateAt24Bits) {
    EXPECT_EQ(StandModel::to_counts(1.0, 100, 21400), 21500);
    EXPECT_EQ(StandModel::to_counts(1e6, 0, 21400), kCountsMax);
    EXPECT_EQ(StandModel::to_counts(-1e6, 0, 21400), kCountsMin);
    EXPECT_EQ(kCountsMax, 0x7FFFFF);
    EXPECT_EQ(kCountsMin, -0x800000);
}

// ---- configuration ----------------------------------------------------------------------------

TEST(PhysicsConfig, TheExampleFileIsTheDefaults) {
    const PhysicsConfig file = load_physics(std::string(DW_SOURCE_DIR) + "/config/physics.example.yaml");
    EXPECT_EQ(to_yaml(file), to_yaml(PhysicsConfig{}));
}

TEST(PhysicsConfig, RoundTripsThroughYaml) {
    PhysicsConfig c;
    dw::physics::effect_type("clock_offset").set(c.effects, {0.118});
    dw::physics::effect_type("cell_crosstalk").set(c.effects, {0.04}, {1, 3});
    dw::physics::effect_type("position_offset").set(c.effects, {0.01, -0.02, 0.03});
    c.jet_model = JetModelKind::jain;
    c.aggregation = Aggregation::velocity_superposition;
    LearntDiscrepancy m;
    m.flight = "a test";
    m.rows = 6, m.inputs = 2, m.coefficients = {1, -2, 3e-5, 4, 5, 6, 7, 8, 9, 10, 11, -12.5};
    m.t0_s = 1, m.t1_s = 9, m.drift_bumps = 3, m.sigma = {0.04, 0.04, 0.06, 0.004, 0.004, 0.006};
    c.discrepancy = {m};
    const PhysicsConfig back = parse_physics(to_yaml(c), "x.yaml");
    EXPECT_EQ(to_yaml(back), to_yaml(c));
    ASSERT_EQ(back.discrepancy.size(), 1u);
    EXPECT_EQ(back.discrepancy[0].coefficients, m.coefficients);
    EXPECT_EQ(back.discrepancy[0].inputs, 2u);
}

// Issue 73: the resimulation's cache is keyed by a configuration's values, not its YAML text.
TEST(PhysicsConfig, ItsKeyIsItsValuesExactly) {
    PhysicsConfig c;
    dw::physics::effect_type("cell_crosstalk").set(c.effects, {0.04}, {1, 3});
    const auto key = key_values(c);
    EXPECT_EQ(key_values(parse_physics(to_yaml(c), "x.yaml")), key) << "what reads back the same keys the same";
    PhysicsConfig d = c;
    dw::physics::effect_type("cell_crosstalk").set(d.effects, {std::nextafter(0.04, 1.0)}, {1, 3});
    EXPECT_NE(key_values(d), key) << "a value's last bit";
    d = c;
    dw::physics::effect_type("cell_crosstalk").set(d.effects, {0.04}, {1, 4});
    EXPECT_NE(key_values(d), key) << "an effect's axes";
    d = c;
    d.aggregation = Aggregation::velocity_superposition;
    EXPECT_NE(key_values(d), key) << "a choice";
    d = c;
    d.classes.push_back({});
    d.classes.back().name = "x";
    const auto with_x = key_values(d);
    EXPECT_NE(with_x, key) << "a list's length";
    d.classes.back().name = "y";
    EXPECT_NE(key_values(d), with_x) << "a text";
}

TEST(PhysicsConfig, ALearntDiscrepancyMustHaveSixRows) {
    EXPECT_EQ(error("discrepancy:\n  - {flight: x, heldout_gain: 0.1, height_lo_m: 0, height_step_m: 0.1, "
                    "height_width_m: 0.1, t0_s: 0, t1_s: 1, drift_bumps: 2, push_top: 1, sigma: [1, 1, 1, 1, 1, 1], "
                    "coefficients: [[1, 2], [3, 4]]}\n"),
              "p.yaml:2:181: discrepancy[0].coefficients: expected six rows, one per axis");
}

TEST(PhysicsConfig, ErrorsNameFileLineAndKey) {
    EXPECT_EQ(
        error("stand:\n  heigth_m: 1.4\n"),
        "p.yaml:2:3: stand.heigth_m: unknown key 'heigth_m' (known: height_m, noise_n, rate_hz; the closest of 8)");
    EXPECT_EQ(error("jet:\n  model: magic\n"),
              "p.yaml:2:10: jet.model: unknown jet model 'magic' (expected bauersfeld or jain)");
    EXPECT_EQ(error("stand:\n  rate_hz: fast\n"), "p.yaml:2:12: stand.rate_hz: expected a number, got 'fast'");
    // A value that swallowed the lines after it (a plain scalar continued over them) is quoted cut
    // short: the message stays one short line (FileFuzzFull.YamlConfiguration found 855 characters).
    EXPECT_EQ(error("stand:\n  rate_hz: eighty hertz or so the datasheet says on a good day\n"),
              "p.yaml:2:12: stand.rate_hz: expected a number, got 'eighty hertz or so the datasheet says on...'");
    EXPECT_EQ(error("air_density_kg_m3: 40\n"), "p.yaml:1:20: air_density_kg_m3: 40 is not in [0.5, 2]");
    EXPECT_NE(error("effects:\n  cell_crosstalk: {from: f_x}\n").find("unknown axis 'f_x'"), std::string::npos);
    EXPECT_NE(error("a: [1,\n").find("p.yaml:"), std::string::npos);
}

// ---- effects: each one's signature ---------------------------------------------------------------

TEST(Effects, ClockOffsetShiftsThePeakByVTimesOffsetFlippingWithDirection) {
    PhysicsConfig base = quiet_config();
    PhysicsConfig off = base;
    dw::physics::effect_type("clock_offset").set(off.effects, {0.1});
    const auto a = simulate_flight(base, over_the_stand(0.3));
    const auto b = simulate_flight(off, over_the_stand(0.3));
    const Peaks pa = peak_positions(a.flight), pb = peak_positions(b.flight);
    EXPECT_NEAR(pb.plus_e - pa.plus_e, 0.5 * 0.1, 0.01);
    EXPECT_NEAR(pb.minus_e - pa.minus_e, -0.5 * 0.1, 0.01);
    // The values are the same samples, stamped offset_s later.
    ASSERT_EQ(a.flight.wrench.size(), b.flight.wrench.size());
    EXPECT_NEAR(b.flight.wrench[100].t - a.flight.wrench[100].t, 0.1, 1e-9);
    EXPECT_EQ(b.flight.wrench[100].w, a.flight.wrench[100].w);
}

TEST(Effects, WakeTransportShiftGrowsWithVerticalSeparation) {
    PhysicsConfig base = quiet_config();
    PhysicsConfig wake = base;
    dw::physics::effect_type("wake_transport").set(wake.effects, {1.0});
    const Jet j = Jet::make(base.neighbour, base);
    double shift_low = 0, shift_high = 0;
    for (double alt : {0.3, 1.3}) {
        const Peaks pa = peak_positions(simulate_flight(base, over_the_stand(alt)).flight);
        const Peaks pb = peak_positions(simulate_flight(wake, over_the_stand(alt)).flight);
        const double plus = pb.plus_e - pa.plus_e, minus = pb.minus_e - pa.minus_e;
        EXPECT_GT(plus, 0.0);   // the force follows where the producer was: seen when it is past
        EXPECT_LT(minus, 0.0);  // ... in either direction
        EXPECT_NEAR(plus, 0.5 * j.transport_delay(alt), 0.4 * 0.5 * j.transport_delay(alt) + 0.003) << alt;
        (alt < 1 ? shift_low : shift_high) = 0.5 * (plus - minus);
    }
    EXPECT_GT(shift_high, 2.5 * shift_low);
}

TEST(Effects, SensorLagDelaysAndSmoothsButDoesNotDependOnSeparation) {
    PhysicsConfig base = quiet_config();
    PhysicsConfig lag = base;
    dw::physics::effect_type("sensor_lag").set(lag.effects, {0.08});
    std::array<double, 2> shifts{};
    for (int i = 0; i < 2; ++i) {
        const double alt = i == 0 ? 0.3 : 1.3;
        const Peaks pa = peak_positions(simulate_flight(base, over_the_stand(alt)).flight);
        const Peaks pb = peak_positions(simulate_flight(lag, over_the_stand(alt)).flight);
        EXPECT_GT(pb.plus_e - pa.plus_e, 0.02);
        EXPECT_LT(pb.minus_e - pa.minus_e, -0.02);
        EXPECT_LT(pb.peak_fd, pa.peak_fd);  // smoothed
        shifts[static_cast<std::size_t>(i)] = 0.5 * ((pb.plus_e - pa.plus_e) - (pb.minus_e - pa.minus_e));
    }
    EXPECT_NEAR(shifts[0], shifts[1], 0.015);
}

TEST(Effects, PositionOffsetShiftsThePeakWithoutFlipping) {
    PhysicsConfig base = quiet_config();
    PhysicsConfig off = base;
    dw::physics::effect_type("position_offset").set(off.effects, {0.0, 0.05, 0.0});
    const Peaks pa = peak_positions(simulate_flight(base, over_the_stand(0.3)).flight);
    const Peaks pb = peak_positions(simulate_flight(off, over_the_stand(0.3)).flight);
    EXPECT_NEAR(pb.plus_e - pa.plus_e, 0.05, 0.005);
    EXPECT_NEAR(pb.minus_e - pa.minus_e, 0.05, 0.005);
}

TEST(Effects, ForceScaleAndCrosstalkChangeOnlyTheRecording) {
    const PhysicsConfig base;  // with noise: the same seed gives the same noise
    PhysicsConfig scaled = base, cross = base;
    dw::physics::effect_type("force_scale").set(scaled.effects, {1.2});
    dw::physics::effect_type("cell_crosstalk").set(cross.effects, {0.05}, {2, 0});
    const auto a = simulate_flight(base, over_the_stand(0.3));
    const auto s = simulate_flight(scaled, over_the_stand(0.3));
    const auto x = simulate_flight(cross, over_the_stand(0.3));
    ASSERT_EQ(a.flight.wrench.size(), s.flight.wrench.size());
    for (std::size_t i = 0; i < a.flight.wrench.size(); i += 97) {
        for (std::size_t k = 0; k < 6; ++k) EXPECT_NEAR(s.flight.wrench[i].w[k], 1.2 * a.flight.wrench[i].w[k], 1e-12);
        EXPECT_NEAR(x.flight.wrench[i].w[0], a.flight.wrench[i].w[0] + 0.05 * a.flight.wrench[i].w[2], 1e-12);
        EXPECT_EQ(x.flight.wrench[i].w[2], a.flight.wrench[i].w[2]);
    }
    EXPECT_EQ(a.truth, s.truth);  // the air did not change
}

TEST(Effects, JetMergingChangesLeaderFollower3At13mButNotASingleProducer) {
    PhysicsConfig base;
    PhysicsConfig merge = base;
    dw::physics::effect_type("jet_merging").switch_on(merge.effects);
    const WrenchModel m_sum(base), m_merge(merge);
    const Vec3 suf(0, 0, -1.4);
    const auto lf3 = make_formation("leader_follower3");
    double peak = 0, max_diff = 0, single_diff = 0;
    for (double n = -1.0; n <= 1.0; n += 0.05) {
        for (double e = -1.0; e <= 1.0; e += 0.05) {
            const Vec3 ref = suf + Vec3(n, e, -1.3);
            std::vector<Producer> ps;
            for (const auto& off : lf3.offsets) ps.push_back(m_sum.producer(ref + off));
            const double a = m_sum.evaluate(suf, ps)[2], b = m_merge.evaluate(suf, ps)[2];
            peak = std::max(peak, std::abs(a));
            max_diff = std::max(max_diff, std::abs(b - a));
            const std::array<Producer, 1> one{m_sum.producer(ref)};
            single_diff = std::max(single_diff, std::abs(m_merge.evaluate(suf, one)[2] - m_sum.evaluate(suf, one)[2]));
        }
    }
    EXPECT_GT(max_diff, 0.2 * peak) << "peak " << peak << " diff " << max_diff;
    EXPECT_EQ(single_diff, 0.0);
    // At 0.3 m the jets are still apart: no merging there.
    std::vector<Producer> low;
    for (const auto& off : lf3.offsets) low.push_back(m_sum.producer(suf + Vec3(0, 0, -0.3) + off));
    EXPECT_EQ(m_merge.evaluate(suf, low), m_sum.evaluate(suf, low));
}

TEST(Effects, FloorRecirculationGrowsWithImpingingJets) {
    PhysicsConfig on;
    dw::physics::effect_type("floor_recirculation").switch_on(on.effects);
    const PhysicsConfig off;
    const WrenchModel with(on), without(off);
    const Vec3 suf(0, 0, -1.4);
    // Producers 1.2 m away: their jets barely touch the sufferer, their recirculation does.
    std::vector<Producer> ps;
    std::vector<double> bias;
    for (int k = 0; k < 3; ++k) {
        ps.push_back(with.producer(suf + Vec3(0.05 * k, 1.2, -1.0)));
        bias.push_back(with.evaluate(suf, ps)[2] - without.evaluate(suf, ps)[2]);
    }
    EXPECT_LT(bias[0], -0.01);  // upward
    EXPECT_NEAR(bias[1] / bias[0], 2.0, 0.05);
    EXPECT_NEAR(bias[2] / bias[0], 3.0, 0.1);
}

TEST(Effects, TurbulenceHasItsIntensityAndTimeScale) {
    Rng rng(3);
    OrnsteinUhlenbeck ou(0.25, 0.025);
    const double dt = 1.0 / 360;
    std::vector<double> x;
    for (int i = 0; i < 400000; ++i) x.push_back(ou.step(dt, rng));
    double var = 0, lag = 0;
    const int k = 9;  // 9 steps = 0.025 s
    for (std::size_t i = 0; i + k < x.size(); ++i) {
        var += x[i] * x[i];
        lag += x[i] * x[i + k];
    }
    EXPECT_NEAR(std::sqrt(var / static_cast<double>(x.size())), 0.25, 0.01);
    EXPECT_NEAR(lag / var, std::exp(-1.0), 0.03);
}

// Lateral buffeting: under one producer the stand's N force (zero in the mean flow on a leg along
// E straight over it) fluctuates by the order the paper measured, 0.05-0.2 N, at every altitude;
// without the jets' lateral turbulence it is at the load cells' noise.
namespace {
constexpr double kOverheadRadius_m = 0.15;  // the neighbour counts as overhead within this

double lateral_rms_overhead(const PhysicsConfig& c, double altitude) {
    FlyOptions o = over_the_stand(altitude);
    o.grid.lines_n_m = {0.0, 0.0, 0.0, 0.0, 0.0, 0.0};
    o.grid.legs = 6;
    const auto f = simulate_flight(c, o).flight;
    const auto tracks = dw::flight::tracks(f);
    const auto& track = tracks[static_cast<std::size_t>(f.find_body(f.meta.neighbours.front()))];
    double sum2 = 0;
    int n = 0;
    for (const auto& s : f.wrench) {
        const auto p = track.position_at(s.t);
        if (std::hypot(p[0], p[1]) > kOverheadRadius_m) continue;
        sum2 += s.w[0] * s.w[0];
        ++n;
    }
    EXPECT_GT(n, 100) << altitude;
    return std::sqrt(sum2 / n);
}
}  // namespace

TEST(Effects, LateralBuffetingIsOfThePapersOrderUnderOneProducer) {
    PhysicsConfig buffeted, calm;
    buffeted.turbulence.lateral_intensity = kLateralIntensity;
    calm.turbulence.lateral_intensity = 0;
    for (double altitude : {0.3, 0.8, 1.3}) {
        const double rms = lateral_rms_overhead(buffeted, altitude);
        const double calm_rms = lateral_rms_overhead(calm, altitude);
        EXPECT_GT(rms, 0.05) << altitude << " m";
        EXPECT_LT(rms, 0.2) << altitude << " m";
        EXPECT_LT(calm_rms, 0.05) << altitude << " m";  // the load cells alone
    }
}

TEST(Effects, LoadCellNoiseIsAboutFiveHundredthsOfANewton) {
    PhysicsConfig c;
    c.turbulence.enabled = false;
    FlyOptions o = over_the_stand(1.3);
    const auto f = simulate_flight(c, o).flight;
    // Before the first leg no neighbour is near: what the stand reports is noise.
    double sum2 = 0;
    int n = 0;
    for (const auto& s : f.wrench) {
        if (s.t > 2.5) break;
        sum2 += s.w[2] * s.w[2];
        ++n;
    }
    const double sd = std::sqrt(sum2 / n);
    EXPECT_GT(sd, 0.02);
    EXPECT_LT(sd, 0.08);
}

// ---- simulated flights ---------------------------------------------------------------------

TEST(Flight, VehiclesFollowTheLegsWithSmallErrorsAndRecordAtTheirRates) {
    const PhysicsConfig c;
    FlyOptions o;
    o.formation = "leader_follower3";
    o.grid.legs = 6;
    const auto r = simulate_flight(c, o);
    const auto& f = r.flight;
    ASSERT_EQ(f.meta.neighbours.size(), 3u);
    EXPECT_EQ(f.meta.formation, "leader_follower");
    ASSERT_EQ(f.legs->size(), 6u);
    const double duration = r.truth_t.back();
    EXPECT_NEAR(static_cast<double>(f.wrench.size()) / duration, 80.0, 1.0);
    EXPECT_NEAR(static_cast<double>(f.poses.size()) / 4.0 / duration, 180.0, 1.0);
    // On a measured leg the middle vehicle moves at the leg speed, within a few cm of the line.
    const auto tracks = dw::flight::tracks(f);
    const auto& v2 = tracks[static_cast<std::size_t>(f.find_body("v2"))];
    const auto& leg = f.legs->front();
    const auto p0 = v2.position_at(leg.t_start + 1.0), p1 = v2.position_at(leg.t_end - 1.0);
    EXPECT_NEAR(std::abs(p1[1] - p0[1]) / (leg.t_end - leg.t_start - 2.0), 0.5, 0.03);
    EXPECT_LT(std::abs(p0[2] - (-1.4 - 0.3)), 0.1);
}

TEST(Flight, AFlyingSuffererSwaysAndIsRecordedAsAResidual) {
    const PhysicsConfig c;
    FlyOptions o;
    o.formation = "single";
    o.grid.legs = 2;
    o.flying_sufferer.enabled = true;
    const auto r = simulate_flight(c, o);
    const auto& f = r.flight;
    EXPECT_FALSE(f.meta.stand_height_m.has_value());
    EXPECT_EQ(f.meta.wrench_source, dw::flight::WrenchSource::residual);
    EXPECT_FALSE(f.meta.moments_measured);
    EXPECT_NEAR(static_cast<double>(f.wrench.size()) / r.truth_t.back(), o.flying_sufferer.rate_hz, 1.0);
    for (const auto& w : f.wrench) ASSERT_EQ(w.w[3] + w.w[4] + w.w[5], 0.0) << "a moment at t = " << w.t;
    // It flies its sway about the stand's point: N over ±sway_n_m, D over ±sway_d_m (within the
    // tracking's lag and wander).
    const auto tracks = dw::flight::tracks(f);
    const auto& s = tracks[static_cast<std::size_t>(f.find_body(f.meta.sufferer))];
    std::array<double, 3> lo{1e9, 1e9, 1e9}, hi{-1e9, -1e9, -1e9};
    for (const auto& p : s.p)
        for (std::size_t k = 0; k < 3; ++k) lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
    EXPECT_NEAR(0.5 * (hi[0] - lo[0]), o.flying_sufferer.sway_n_m, 0.1);
    EXPECT_NEAR(0.5 * (hi[2] - lo[2]), o.flying_sufferer.sway_d_m, 0.1);
    EXPECT_NEAR(0.5 * (hi[2] + lo[2]), -c.stand.height_m, 0.1);
    EXPECT_LT(hi[1] - lo[1], 0.2);
    // An option out of its range is one error naming it (a zero rate would never end).
    auto bad = o;
    bad.flying_sufferer.rate_hz = 0;
    try {
        simulate_flight(c, bad);
        ADD_FAILURE() << "a zero residual rate was accepted";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("rate_hz 0 is not in"), std::string::npos) << e.what();
    }
    // On the stand, the same options give the stand's flight (the sway's stream drawn apart).
    o.flying_sufferer.enabled = false;
    EXPECT_TRUE(simulate_flight(c, o).flight.meta.stand_height_m.has_value());
}

TEST(Flight, SameSeedSameBytesOtherSeedOtherNoise) {
    const PhysicsConfig c;
    FlyOptions o;
    o.formation = "side_by_side";
    o.grid.legs = 3;
    const auto a = simulate_flight(c, o), b = simulate_flight(c, o);
    EXPECT_EQ(a.truth, b.truth);
    ASSERT_EQ(a.flight.wrench.size(), b.flight.wrench.size());
    for (std::size_t i = 0; i < a.flight.wrench.size(); ++i) ASSERT_EQ(a.flight.wrench[i].w, b.flight.wrench[i].w);
    o.seed = 2;
    const auto d = simulate_flight(c, o);
    EXPECT_NE(d.flight.wrench[50].w, a.flight.wrench[50].w);
}

TEST(Jet, JainGaussianAlternative) {
    PhysicsConfig c;
    c.jet_model = JetModelKind::jain;
    const Jet j = Jet::make(c.neighbour, c);
    const double s = 1.3, z = s - c.jain.z0_m;
    EXPECT_NEAR(j.centreline(s), j.u_hover * c.jain.c_ax * c.jain.diameter_m / z, 1e-12);
    EXPECT_NEAR(j.axial(j.half_width(s), s), 0.5 * j.centreline(s), 1e-12);
    EXPECT_NEAR(j.axial(0.1, s), j.centreline(s) * std::exp(-c.jain.c_rad * (0.1 / z) * (0.1 / z)), 1e-12);
    EXPECT_EQ(j.radial(0.1, s), 0.0);
    // The whole simulator runs on it.
    const WrenchModel m(c);
    const std::array<Producer, 1> ps{m.producer(Vec3(0, 0, -2.7))};
    EXPECT_GT(m.evaluate(Vec3(0, 0, -1.4), ps)[2], 0.5);
}

// ---- issue 14: physics that lies -----------------------------------------------------------------

namespace {
double peak_fd(const dw::flight::Flight& f) {
    double peak = 0;
    for (const auto& s : f.wrench) peak = std::max(peak, std::abs(s.w[2]));
    return peak;
}
}  // namespace

// Jain jets merged by jet_merging were NaN: zeros for stack, a saturated ±401 397 N for the rest.
TEST(PhysicsHardening, JainJetsMergeIntoFiniteForcesOfTheRightSize) {
    PhysicsConfig jain = quiet_config();
    jain.jet_model = dw::physics::JetModelKind::jain;
    PhysicsConfig merged = jain;
    dw::physics::effect_type("jet_merging").switch_on(merged.effects);
    for (const char* formation : {"stack", "side_by_side", "leader_follower3", "hybrid"}) {
        const double plain = peak_fd(simulate_flight(jain, over_the_stand(0.8, formation)).flight);
        const double with = peak_fd(simulate_flight(merged, over_the_stand(0.8, formation)).flight);
        EXPECT_GT(with, 0.25 * plain) << formation;  // merging redistributes momentum, it does not erase it
        EXPECT_LT(with, 4.0 * plain) << formation;
        EXPECT_LT(with, 100.0) << formation;  // nowhere near the HX711's saturation
    }
}

TEST(PhysicsHardening, DivergingDynamicsAreAnErrorNotHugeNumbers) {
    PhysicsConfig stiff = quiet_config();
    stiff.dynamics.natural_frequency_rad_s = 50;
    stiff.dynamics.damping = 5;
    stiff.dynamics.rate_hz = 200;  // explicit integration of a 500 1/s damping term at 200 Hz: unstable
    try {
        simulate_flight(stiff, over_the_stand(0.8));
        FAIL() << "a diverging simulation was accepted";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("diverged"), std::string::npos) << e.what();
    }
}

TEST(PhysicsHardening, DuplicateKeysAndNonFiniteOffsetsAreRefused) {
    EXPECT_EQ(error("air_density_kg_m3: 1.2\nair_density_kg_m3: 1.1\n"),
              "p.yaml:2:1: key 'air_density_kg_m3' appears twice in the same mapping");
    EXPECT_NE(
        error("effects:\n  position_offset: {enabled: true, offset_m: [.nan, 0, 0]}\n").find("not a finite number"),
        std::string::npos);
    EXPECT_NE(error("stand: {noise_n: .inf}\n").find("not a finite number"), std::string::npos);
}

// Issue 44: one recording chain. Each stage acts once, in the chain's order, and the sensor's
// recurrence gives the same readings to a whole series and to a live stream.
TEST(RecordingChain, EachStageActsOnceAndLiveReadingsAreTheSeriesReadings) {
    dw::physics::Effects fx;
    dw::physics::effect_type("sensor_lag").set(fx, {0.05});
    dw::physics::effect_type("force_scale").set(fx, {1.2});
    dw::physics::effect_type("cell_crosstalk").set(fx, {0.1}, {2, 0});  // f_d leaks into f_n
    dw::physics::effect_type("clock_offset").set(fx, {0.03});
    dw::physics::effect_type("position_offset").set(fx, {0.1, -0.2, 0.0});
    const dw::physics::RecordingChain chain(fx);
    EXPECT_DOUBLE_EQ(chain.clock_delay_s(), 0.03);
    EXPECT_EQ(chain.position_error_m(), dw::physics::Vec3(0.1, -0.2, 0.0));
    dw::physics::Wrench6 w{0, 0, 1, 0, 0, 0};
    chain.calibration(w);  // the gain, then the leak of the recorded (gained) f_d
    EXPECT_DOUBLE_EQ(w[2], 1.2);
    EXPECT_DOUBLE_EQ(w[0], 0.1 * 1.2);

    std::vector<double> t;
    dw::physics::RecordedWrench series;
    for (int i = 0; i < 400; ++i) {  // irregular stamps, a step and a ramp
        t.push_back(0.004 * i + 0.001 * (i % 3));
        series.push_back({0, 0, t.back() < 0.5 ? 0.0 : 1.0 + t.back(), 0, 0, 0});
    }
    auto whole = series;
    chain.sensor(t, whole);
    dw::physics::RecordingChain::SensorStream live(chain);
    for (std::size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(live.read(t[i], series[i])[2], whole[i][2], 1e-12) << i;
    // A first-order lag: 63 % of a step after one time constant (the ramp adds a little).
    std::size_t k = 0;
    while (t[k] < 0.5 + 0.05) ++k;
    EXPECT_NEAR(whole[k][2] / series[k][2], 1 - std::exp(-1.0), 0.05);
    // Nothing on: the series is what the sensor reads.
    const dw::physics::Effects none;
    auto untouched = series;
    dw::physics::RecordingChain(none).sensor(t, untouched);
    EXPECT_EQ(untouched, series);
}

// Issue 73: the replay's sampler is the chips' hold, axis by axis. A frame holds chip 0's fresh
// conversion and the other seven chips' latest, each on average half a period old, so f_d (four
// vertical cells, chip 0 among them) is 3/8 of a period old and f_n, f_e half a period. On a ramp
// on every force, over many stands (random phases and rates, no noise: one stand's chips of nearly
// one rate keep their phases), the chips and the replay's sampler at the chips' own stamps agree
// on average to a small share of what one age for all (7/16 of a period, the replay's before)
// misses on f_d.
TEST(RecordingChain, TheReplaysSamplerAgesEachAxisAsTheChipsDo) {
    StandParams p;
    p.noise_n = 0;
    p.offset_sigma_counts = 0;
    constexpr double kSlope = 1.0;  // N/s on every force; the moments nil
    constexpr int kStands = 100;
    std::vector<double> t;
    RecordedWrench felt;
    for (int i = 0; i <= 5000; ++i) {  // 5 s at 1 kHz
        t.push_back(0.001 * i);
        felt.push_back({kSlope * t.back(), kSlope * t.back(), kSlope * t.back(), 0, 0, 0});
    }
    const double one_age = 7.0 / 16.0 / p.rate_hz, step = kSlope / p.rate_hz / 16;  // 7/16 against 3/8 or 1/2
    Wrench6 bias{}, bias_one_age{};  // the chips' recording less the replay's, on average
    for (int seed = 1; seed <= kStands; ++seed) {
        Rng rng(static_cast<std::uint64_t>(seed));
        ChipSampler chips(p, rng);
        const Samples a = chips.sample(t, felt, 0.0);
        StampSampler replay(a.stamps, &p);
        const Samples b = replay.sample(t, felt, 0.0);
        const double n = static_cast<double>(a.w.size()) * kStands;
        for (std::size_t i = 0; i < a.w.size(); ++i) {
            for (std::size_t ax = 0; ax < 6; ++ax) {
                bias[ax] += (a.w[i][ax] - b.w[i][ax]) / n;
                bias_one_age[ax] += (a.w[i][ax] - kSlope * (a.stamps[i] - one_age) * (ax < 3)) / n;
            }
        }
    }
    for (std::size_t ax = 0; ax < 6; ++ax) {
        std::printf("axis %zu: the chips less the replay %+.6f, less one age for all %+.6f\n", ax, bias[ax],
                    bias_one_age[ax]);
        EXPECT_LT(std::abs(bias[ax]), 0.25 * step) << "axis " << ax;
    }
    EXPECT_GT(bias_one_age[2], 0.75 * step);   // f_d: younger than one age for all
    EXPECT_LT(bias_one_age[0], -0.75 * step);  // f_n: older
}

// Issue 71: the prediction's noise model. Residuals drawn with a known push share and timing
// spread about pushes and rates of either size are fitted back by maximum likelihood; a push's
// rate is its change across the span, offline and online; and the calibrated model is the one a
// configuration serves, else 2 I from its turbulence.
TEST(PredictionNoise, TheFitRecoversAKnownPushShareAndTimingSpread) {
    using dw::physics::NoiseSample;
    constexpr double kShare = 0.4, kSpread_s = 0.06, kFloor = 0.005;
    std::mt19937 rng(71);
    std::normal_distribution<double> unit(0, 1);
    std::uniform_real_distribution<double> push(0, 0.1), rate(-0.5, 0.5);
    std::vector<NoiseSample> samples;
    for (int i = 0; i < 40000; ++i) {
        NoiseSample s{0, kFloor, push(rng), rate(rng)};
        s.residual = unit(rng) * dw::physics::prediction_sd(kFloor, {kShare, kSpread_s}, s.p, s.p_rate);
        samples.push_back(s);
    }
    const auto n = dw::physics::fit_prediction_noise(samples);
    EXPECT_NEAR(n.push_share, kShare, 0.03 * kShare);
    EXPECT_NEAR(n.timing_spread_s, kSpread_s, 0.03 * kSpread_s);
    for (auto& s : samples)
        s.p_rate = 0, s.residual = unit(rng) * dw::physics::prediction_sd(kFloor, {kShare, 0}, s.p, 0);
    EXPECT_LT(dw::physics::fit_prediction_noise(samples).timing_spread_s, 0.01) << "no rate, no timing spread";

    std::vector<double> t, p;
    for (int i = 0; i < 100; ++i) t.push_back(0.01 * i), p.push_back(i < 50 ? 0.3 * t.back() : 0.0);
    const auto r = dw::physics::push_rates(t, p);
    EXPECT_NEAR(r[20], 0.3, 1e-9) << "a ramp's slope";
    EXPECT_NEAR(r[90], 0.0, 1e-9) << "flat";
    EXPECT_LT(r[50], 0.0) << "the ramp's fall";
    dw::physics::PushRate online;
    double last = 0;
    for (int i = 0; i < 30; ++i) last = online.update(t[static_cast<std::size_t>(i)], p[static_cast<std::size_t>(i)]);
    EXPECT_NEAR(last, 0.3, 1e-9);

    dw::physics::PhysicsConfig c;
    c.turbulence.intensity = 0.1;
    EXPECT_DOUBLE_EQ(dw::physics::prediction_noise_of(c).push_share, 0.2);
    EXPECT_DOUBLE_EQ(dw::physics::prediction_noise_of(c).timing_spread_s, 0.0);
    c.prediction_noise = {0.5, 0.07};
    EXPECT_DOUBLE_EQ(dw::physics::prediction_noise_of(c).push_share, 0.5);
    EXPECT_DOUBLE_EQ(dw::physics::prediction_noise_of(c).timing_spread_s, 0.07);
}
