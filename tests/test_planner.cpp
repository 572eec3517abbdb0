// The planner's plans: formation geometry, coverage of the square, separation and geofence over
// a fine time grid for every formation, infeasible plans rejected with the reason, the picture.
#include <gtest/gtest.h>

#include <filesystem>

#include "core/errors.hpp"
#include "swarm_planner/ground_tie.hpp"
#include "swarm_planner/picture.hpp"
#include "swarm_planner/plan.hpp"
#include "swarm_planner/vehicle_link.hpp"
#include <cmath>

#include "support.hpp"

using namespace dw::planner;

TEST(Formations, HaveTheStudysGeometry) {
    using dw::physics::make_formation;
    EXPECT_EQ(make_formation("single").offsets.size(), 1u);
    const auto sbs = make_formation("side_by_side").offsets;  // abreast: across the E travel
    ASSERT_EQ(sbs.size(), 2u);
    EXPECT_NEAR(sbs[0].y(), sbs[1].y(), 1e-12);
    EXPECT_GT(std::abs(sbs[0].x() - sbs[1].x()), 0.3);
    const auto lf3 = make_formation("leader_follower3").offsets;  // in line along E, 0.5 m from the centroid
    ASSERT_EQ(lf3.size(), 3u);
    for (const auto& o : lf3) EXPECT_NEAR(o.x(), 0.0, 1e-12);
    EXPECT_NEAR((lf3[0] + lf3[1] + lf3[2]).norm(), 0.0, 1e-12);
    EXPECT_NEAR(std::abs(lf3[0].y()), 0.5, 1e-12);
    const auto stack = make_formation("stack").offsets;  // different altitudes, small lateral offset
    ASSERT_EQ(stack.size(), 2u);
    EXPECT_GT(std::abs(stack[0].z() - stack[1].z()), 0.3);
    EXPECT_LT(std::hypot(stack[0].x() - stack[1].x(), stack[0].y() - stack[1].y()), 0.2);
    const auto hyb = make_formation("hybrid").offsets;  // equilateral triangle, one plane
    ASSERT_EQ(hyb.size(), 3u);
    const double s01 = (hyb[0] - hyb[1]).norm(), s12 = (hyb[1] - hyb[2]).norm(), s20 = (hyb[2] - hyb[0]).norm();
    EXPECT_NEAR(s01, s12, 1e-9);
    EXPECT_NEAR(s12, s20, 1e-9);
    for (const auto& o : hyb) EXPECT_EQ(o.z(), 0.0);
    EXPECT_THROW(make_formation("diamond"), dw::InputError);
}

TEST(Plans, EveryFormationIsSafeOverAFineTimeGridAndCoversTheSquare) {
    for (const auto& name : dw::physics::formation_names()) {
        SCOPED_TRACE(name);
        PlanOptions o;
        o.formation = name;
        o.check_dt_s = 0.005;
        const Plan p = make_plan(o);
        EXPECT_EQ(p.reference.legs().size(), 36u);
        const auto v = check(p);
        EXPECT_FALSE(v.has_value()) << v->what;
        EXPECT_GE(coverage(p), 0.95);
        // Legs alternate +E/-E and are at constant speed on their measured segment.
        for (std::size_t i = 0; i < p.reference.legs().size(); ++i) {
            const auto& leg = p.reference.legs()[i];
            EXPECT_EQ(leg.direction, i % 2 == 0 ? 1 : -1);
            for (double t = leg.t_start + 0.05; t < leg.t_end; t += 0.5) {
                EXPECT_NEAR(p.reference.at(t).velocity.norm(), 0.5, 1e-9);
            }
        }
    }
}

TEST(Plans, InfeasiblePlansAreRejectedWithTheReason) {
    PlanOptions close;
    close.formation = "leader_follower3";
    close.min_separation_m = 0.6;  // the vehicles fly 0.5 m apart
    const auto v = check(make_plan(close));
    ASSERT_TRUE(v.has_value());
    EXPECT_NE(v->what.find("v1 and v2 come 0.5 m apart"), std::string::npos) << v->what;
    EXPECT_NE(v->what.find("minimum 0.6 m"), std::string::npos);

    PlanOptions low;
    low.formation = "single";
    low.grid.altitudes_m = {0.1};  // 10 cm over the sufferer
    const auto w = check(make_plan(low));
    ASSERT_TRUE(w.has_value());
    EXPECT_NE(w->what.find("from the sufferer"), std::string::npos) << w->what;

    PlanOptions tight;
    tight.formation = "side_by_side";
    tight.fence.e_min = -1.2;  // the run-up leaves the room
    const auto x = check(make_plan(tight));
    ASSERT_TRUE(x.has_value());
    EXPECT_NE(x->what.find("leaves the geofence"), std::string::npos) << x->what;
}

TEST(Plans, DocumentsAndPicture) {
    PlanOptions o;
    o.formation = "hybrid";
    o.grid.legs = 6;
    const Plan p = make_plan(o);
    const std::string yaml = to_document(p, false), json = to_document(p, true);
    EXPECT_NE(yaml.find("format: downwash-plan/1"), std::string::npos);
    EXPECT_NE(json.find("\"legs\""), std::string::npos);
    dw::test::TempDir d;
    draw_plan(p, d.file("plan.png"));
    const std::string png = dw::read_file(d.file("plan.png"));
    ASSERT_GT(png.size(), 1000u);
    EXPECT_EQ(png.substr(1, 3), "PNG");
}

// ---- issue 14: NaN never flies -------------------------------------------------------------------

TEST(PlannerHardening, ChecksArePositivelySatisfiedSoNaNFailsThem) {
    const Geofence fence;
    const double nan = std::nan("");
    EXPECT_TRUE(fence.contains({0, 0, -1.5}, 0));
    EXPECT_FALSE(fence.contains({nan, 0, -1.5}, 0));
    EXPECT_FALSE(fence.contains({0, 0, -1.5}, nan));
    dw::physics::Setpoint sp;
    EXPECT_TRUE(is_finite(sp));
    sp.velocity.y() = INFINITY;
    EXPECT_FALSE(is_finite(sp));
}

TEST(PlannerHardening, NaNOptionsNeverMakeAPlan) {
    for (int which = 0; which < 3; ++which) {
        PlanOptions o;
        o.grid.legs = 2;
        if (which == 0) o.grid.altitudes_m = {std::nan("")};
        if (which == 1) o.grid.speed_mps = std::nan("");
        if (which == 2) o.min_separation_m = std::nan("");
        EXPECT_THROW(make_plan(o), dw::InputError) << which;
    }
}

TEST(PlannerHardening, ChecksStopWhenAsked) {
    PlanOptions o;
    o.grid.legs = 4;
    const Plan p = make_plan(o);
    std::stop_source stop;
    stop.request_stop();
    EXPECT_THROW(check(p, stop.get_token()), dw::Stopped);
    EXPECT_THROW(coverage(p, stop.get_token()), dw::Stopped);
    EXPECT_FALSE(check(p));
}

// Issue 70: the last gate before every command sits in the vehicle link, whatever the planner
// computed. A setpoint that is not finite or lies outside the room never reaches a vehicle: it
// holds its last setpoint that passed, at rest, or is sent nothing if none has passed.
namespace {
class RecordingLink final : public VehicleLink {
public:
    std::vector<std::vector<std::optional<dw::physics::Setpoint>>> delivered;
    std::vector<std::optional<double>> down;  // where each vehicle is, as the link knows it

private:
    void deliver(const std::vector<std::optional<dw::physics::Setpoint>>& sps, dw::Nanos) override {
        delivered.push_back(sps);
    }
    std::optional<double> down_of(std::size_t i) override { return i < down.size() ? down[i] : std::nullopt; }
};
dw::physics::Setpoint at(double n, double e, double d) {
    dw::physics::Setpoint s;
    s.position = {n, e, d};
    s.velocity = {0.5, 0, 0};
    return s;
}
}  // namespace

TEST(VehicleLinkGate, NothingNonFiniteOrOutsideTheRoomReachesAVehicle) {
    RecordingLink link;  // the default room: N ±2, E ±3, D -4..0
    const double nan = std::nan("");
    // v1 starts outside the room (a parked pose 50 m away), v2 with a NaN: neither gets anything.
    link.send({at(50, 0, -1), at(nan, 0, -1)}, 0);
    ASSERT_EQ(link.delivered.size(), 1u);
    EXPECT_FALSE(link.delivered[0][0].has_value());
    EXPECT_FALSE(link.delivered[0][1].has_value());
    // Inside the room both pass as computed.
    link.send({at(0, 1, -1), at(1, -1, -1.5)}, 1);
    ASSERT_TRUE(link.delivered[1][0] && link.delivered[1][1]);
    EXPECT_DOUBLE_EQ(link.delivered[1][0]->velocity.x(), 0.5);
    // Then 5 m below the floor, 1e300 m away, an infinite yaw: each holds its last, at rest.
    auto yaw = at(0, 0, -1);
    yaw.yaw_rad = INFINITY;
    for (const auto& bad : {at(0, 0, 5), at(1e300, 0, -1), yaw}) {
        link.send({bad, at(1, -1, -1.5)}, 2);
        const auto& got = link.delivered.back();
        ASSERT_TRUE(got[0].has_value());
        EXPECT_TRUE(got[0]->position.isApprox(dw::physics::Vec3(0, 1, -1)));
        EXPECT_TRUE(got[0]->velocity.isZero());
        EXPECT_TRUE(got[0]->acceleration.isZero());
        EXPECT_DOUBLE_EQ(got[1]->velocity.x(), 0.5);  // the other vehicle is untouched
    }
    EXPECT_EQ(link.refused(), 5u);
    // A fence of the lab's own: what the default room allows may be outside it.
    Geofence small;
    small.n_min = -0.5, small.n_max = 0.5;
    link.set_fence(small);
    link.send({at(0, 1, -1), at(1, -1, -1.5)}, 3);
    EXPECT_TRUE(link.delivered.back()[1]->velocity.isZero());  // v2 held at rest, not sent to N = 1
}

// Issue 69: from an abort or a landing on, the gate lets a vehicle only go down. The lab's frame and
// the link's disagree on purpose (PX4's origin 2.6 m off the floor): the planner descends "to the
// floor" at D = 0, which for the link is far above the vehicle. No setpoint is delivered above where
// the link knows the vehicle is, nor above what it was last sent; nothing that lifts.
TEST(VehicleLinkGate, InDescentNoVehicleIsSentAboveWhereItIsWhateverTheFramesSay) {
    RecordingLink link;
    link.send({at(0, 0, -1.5), at(1, 0, -1.0)}, 0);  // in flight: as computed
    EXPECT_DOUBLE_EQ(link.delivered.back()[0]->position.z(), -1.5);
    link.begin_descent();
    // v1: the link sees it at D = -1.2 (lower than its setpoint: it lags on a climb); holding the
    // planner's last setpoint would lift it — it is held where it is. v2: its estimate unknown.
    link.down = {-1.2, std::nullopt};
    auto up = at(0, 0, -2.6);
    up.velocity = {0, 0, -0.4};
    up.acceleration = {0, 0, -1};
    link.send({up, at(1, 0, -1.4)}, 1);
    const auto& a = link.delivered.back();
    EXPECT_DOUBLE_EQ(a[0]->position.z(), -1.2);
    EXPECT_DOUBLE_EQ(a[0]->velocity.z(), 0);
    EXPECT_DOUBLE_EQ(a[0]->acceleration.z(), 0);
    EXPECT_DOUBLE_EQ(a[1]->position.z(), -1.0);  // unknown: never above what it was last sent
    // As each comes down, the ratchet follows; a descent the planner computes passes as computed.
    link.down = {-0.9, -0.95};
    link.send({at(0, 0, -1.5), at(1, 0, -0.5)}, 2);
    EXPECT_DOUBLE_EQ(link.delivered.back()[0]->position.z(), -0.9);
    EXPECT_DOUBLE_EQ(link.delivered.back()[1]->position.z(), -0.5);
    EXPECT_DOUBLE_EQ(link.delivered.back()[1]->velocity.x(), 0.5);
    // The estimate jumps up (a reset): the last delivered D still holds it down.
    link.down = {-3.0, -3.0};
    link.send({at(0, 0, -2.0), at(1, 0, -2.0)}, 3);
    EXPECT_DOUBLE_EQ(link.delivered.back()[0]->position.z(), -0.9);
    EXPECT_DOUBLE_EQ(link.delivered.back()[1]->position.z(), -0.5);
    // Below the floor is where a landing ends (the frames disagree): allowed, not refused.
    link.down = {2.6, 2.6};
    link.send({at(0, 0, 0), at(1, 0, 0)}, 4);
    EXPECT_DOUBLE_EQ(link.delivered.back()[0]->position.z(), 2.6);
    EXPECT_EQ(link.refused(), 0u);
    for (const auto& step : link.delivered)
        for (const auto& sp : step) EXPECT_TRUE(sp.has_value());
}

// Issue 69, point 3: a PX4 on its own sensors has its origin metres off the floor, and its estimate
// wanders on the ground. The tie is the latest still window's median D while PX4 says disarmed,
// frozen from the arming on; an estimate that moves too much is not tied, and says why.
TEST(GroundTie, TheFloorIsTheStillEstimateOnTheGroundFrozenAtArming) {
    using dw::planner::GroundTie;
    GroundTie tie;
    const dw::physics::Vec3 still = dw::physics::Vec3::Zero();
    double t = 0;
    const auto feed = [&](double seconds, double d, double drift_mps, bool disarmed, double wobble = 0.02) {
        for (const double end = t + seconds; t < end; t += 0.01)
            tie.add(t, {0.1, -0.2, d + drift_mps * t + wobble * std::sin(40 * t)}, still, disarmed);
    };
    feed(1.0, 1.6, 0, true);
    EXPECT_FALSE(tie.tied()) << "not before a whole window";
    EXPECT_NE(tie.describe().find("no steady estimate"), std::string::npos) << tie.describe();
    feed(2.0, 1.6, 0, true);
    ASSERT_TRUE(tie.tied());
    EXPECT_NEAR(*tie.floor_d(), 1.6, 0.03);
    EXPECT_NE(tie.describe().find("1.60 m above the floor"), std::string::npos) << tie.describe();
    // It drifts while it waits (a barometer): the tie follows the latest still window...
    feed(4.0, 1.6 - 0.02 * 3, 0.02, true);
    const double at_arming = *tie.floor_d();
    EXPECT_GT(at_arming, 1.62);
    // ... and is frozen once armed: a climb of 2 m is not the floor.
    feed(3.0, at_arming - 2.0, 0, false);
    EXPECT_DOUBLE_EQ(*tie.floor_d(), at_arming);
    // An estimate that jumps about on the ground is not tied.
    GroundTie shaky;
    for (double u = 0; u < 4; u += 0.01) shaky.add(u, {0, 0, 1.0 + 0.4 * std::sin(3 * u)}, still, true);
    EXPECT_FALSE(shaky.tied());
    EXPECT_NE(shaky.describe().find("not steady"), std::string::npos) << shaky.describe();
    // Nor one that moves (carried, or climbing).
    GroundTie moving;
    for (double u = 0; u < 4; u += 0.01) moving.add(u, {0, 0, 1.0}, {0, 0, -1.0}, true);
    EXPECT_FALSE(moving.tied());
}
