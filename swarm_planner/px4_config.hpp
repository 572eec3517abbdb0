#pragma once
// Per-vehicle PX4 settings for `dw-planner run --vehicles px4 [--px4 FILE]` (docs/OPERATOR.md):
//
//   version: "1.15"          # 1.14, 1.15 or 1.16 (dds/px4.hpp)
//   odometry: planner        # who feeds mocap to each PX4's estimator: planner, bridge or off
//   odometry_hz: 50          # mocap into each PX4's estimator (vehicle_visual_odometry); 0 = every frame
//   takeoff_ramp_s: 3        # the vehicles' MPC_TKO_RAMP_T (no tracking bound until airborne that long)
//   vehicles:
//     v1: {namespace: px4_1, system_id: 2, origin_m: [0, 0, 0], heading_deg: 0}
//
// `namespace` is the -n of the vehicle's uXRCE-DDS client start line; `system_id` its MAV_SYS_ID
// (commands go to it); `origin_m` (lab NED) and `heading_deg` place PX4's local frame in the lab:
// local = Rz(-heading) (lab - origin). Without a file: namespace = the vehicle's name, system id
// = its index + 1 (as PX4 SITL numbers its instances' MAV_SYS_ID), origin 0, heading 0.
#include <Eigen/Geometry>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/numbers.hpp"
#include "dds/px4.hpp"
#include "physics/vehicle.hpp"

namespace dw::planner {

inline constexpr Range kSystemIdRange{1, 254};
inline constexpr Range kOdometryRateRange{0, 500, "Hz"};
inline constexpr Range kAnswerTimeoutRange{0.05, 10, "s"};
inline constexpr Range kAttemptsRange{1, 10};
inline constexpr Range kStatusTimeoutRange{0.2, 30, "s"};
inline constexpr Range kLandTimeoutRange{1, 600, "s"};
inline constexpr Range kEstimatorTimeoutRange{0, 600, "s"};
inline constexpr Range kTakeoffRampRange{0, 30, "s"};  // PX4's MPC_TKO_RAMP_T is 0-5 s
inline constexpr Range kHeadingRange{-360, 360, "deg"};
inline constexpr Range kOriginRange{-100, 100, "m"};
inline constexpr Range kStdRange{1e-6, 10};

struct Px4Vehicle {
    std::string name;                              // the plan's vehicle (v1, v2, ...)
    std::string ns;                                // its client's -n; "" = rt/fmu/...
    int system_id = 1;                             // MAV_SYS_ID
    physics::Vec3 origin = physics::Vec3::Zero();  // PX4's local origin in lab NED [m]
    double heading_rad = 0;                        // PX4's local north, from the lab's north towards east
};

// Who feeds the motion capture to PX4's estimator (vehicle_visual_odometry, swarm_planner/px4_odometry.hpp):
// the planner's link while it runs; the mocap bridge whenever a vehicle is tracked
// (dw-mocap-bridge --feed-px4: the estimator has warmed up before anyone arms); or no one (a PX4 on
// its own sensors: GPS, optical flow, SITL's ground truth).
enum class OdometryBy { planner, bridge, off };
inline constexpr const char* kOdometryByNames[] = {"planner", "bridge", "off"};  // OdometryBy's values in order

// Where each PX4 local frame's floor is: `file` — its origin_m says it (a PX4 on the lab's visual
// odometry, whose estimator works in the lab's frame); `estimate` — PX4's own estimate on the ground
// (a PX4 on its own sensors: its origin is where its GPS and barometer put it, metres off the floor,
// and it moves between boots), tied once by swarm_planner/ground_tie.hpp; origin_m then gives N, E.
enum class GroundFrom { file, estimate };
inline constexpr const char* kGroundFromNames[] = {"file", "estimate"};  // GroundFrom's values in order

struct Px4Options {
    dds::Px4Version version = dds::Px4Version::v1_15;
    OdometryBy odometry = OdometryBy::planner;
    double odometry_hz = 50;        // 0 = every mocap frame
    double position_std_m = 0.005;  // the variances sent with the odometry
    double orientation_std_rad = 0.01;
    double velocity_std_mps = 0.05;
    double answer_timeout_s = 1.0;  // per command attempt, waiting for vehicle_status to show it
    int attempts = 3;
    double status_timeout_s = 3.0;      // the first vehicle_status within this; in flight, one older is a lost link
    double land_timeout_s = 30.0;       // after NAV_LAND, PX4 must report every vehicle disarmed within this
    double estimator_timeout_s = 30.0;  // before OFFBOARD, the wait for PX4's pre-flight checks to pass
    double takeoff_ramp_s = 3.0;        // PX4's MPC_TKO_RAMP_T: after lift-off, no tracking bound for this long
    GroundFrom ground = GroundFrom::file;
    std::vector<Px4Vehicle> vehicles;  // in the plan's order
};

// Where a vehicle's PX4 local frame sits in the lab: local = Rz(-heading) (lab - origin), both NED.
struct LocalFrame {
    physics::Vec3 origin = physics::Vec3::Zero();
    double heading_rad = 0;

    Eigen::Matrix3d lab_to_local() const {
        return Eigen::AngleAxisd(-heading_rad, physics::Vec3::UnitZ()).toRotationMatrix();
    }
    physics::Vec3 point(const physics::Vec3& lab) const { return lab_to_local() * (lab - origin); }
    physics::Vec3 vector(const physics::Vec3& lab) const { return lab_to_local() * lab; }
    physics::Vec3 lab_point(const physics::Vec3& local) const { return origin + lab_to_local().transpose() * local; }
    physics::Vec3 lab_vector(const physics::Vec3& local) const { return lab_to_local().transpose() * local; }
    Eigen::Quaterniond attitude(const Eigen::Quaterniond& body_to_lab) const {
        return Eigen::Quaterniond(lab_to_local()) * body_to_lab;
    }
    Eigen::Quaterniond lab_attitude(const Eigen::Quaterniond& body_to_local) const {
        return Eigen::Quaterniond(lab_to_local().transpose()) * body_to_local;
    }
    double yaw(double lab_yaw) const { return std::remainder(lab_yaw - heading_rad, 2 * std::numbers::pi); }
};
inline LocalFrame local_frame(const Px4Vehicle& v) { return {v.origin, v.heading_rad}; }

// A pose LocalFrame can carry between the lab and PX4: a plausible position and orientation.
inline bool usable_pose(const physics::Vec3& x, const Eigen::Quaterniond& q) {
    return physics::plausible_position(x) && physics::plausible_orientation(q.coeffs());
}
// A velocity PX4 may be given; otherwise it is sent as unknown (PX4's NaN), never as inf.
inline bool usable_velocity(const physics::Vec3& v) {
    return v.allFinite() && v.norm() <= physics::kMaxPlausibleSpeedMps;
}

// The defaults for the plan's vehicles (see above).
Px4Options default_px4_options(const std::vector<std::string>& plan_vehicles);
// Reads the file; every plan vehicle must be listed, nothing else may be. Errors are
// dw::InputError "file:line:col: key: problem".
Px4Options load_px4_options(const std::string& path, const std::vector<std::string>& plan_vehicles);

}  // namespace dw::planner
