#pragma once
// The planner's plans: a formation (the study's defaults), grid legs over the square centred on
// the stand, the smooth reference trajectory, and the checks that make a plan flyable — every
// pair of vehicles (and the sufferer on its stand) at least the minimum separation apart, and
// everything inside the room's geofence, over a fine time grid.
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "physics/trajectory.hpp"

namespace dw::planner {

// The vehicles stay below the stand's volume ceiling; the separation is what the checks keep.
inline constexpr Range kPlanAltitudeRange{physics::kAltitudeRange.lo, 1.4, "m"};
inline constexpr Range kSeparationRange{0.05, 5, "m"};

using physics::is_finite;  // what the planner sends to a vehicle must pass it

struct Geofence {
    double n_min = -2.0, n_max = 2.0;  // a 4 m x 6 m x 4 m room (96 m³) around the stand
    double e_min = -3.0, e_max = 3.0;
    double d_min = -4.0, d_max = 0.0;  // ceiling 4 m above the floor (D = 0): a Stack at 1.3 m
                                       // puts its upper vehicle 3.2 m up
    double margin_m = 0.2;
    // What a measured or commanded position may stray beyond the fence before it counts as outside:
    // hover noise on the floor or at a wall, a vehicle parked on the floor (D a little above 0).
    static constexpr double kTolerance_m = 0.1;
    // True only when x is finite and inside the fence grown by `grow_m` (negative: shrunk).
    bool contains(const physics::Vec3& x, double grow_m) const;
    // A measured position (mocap, PX4's estimate): inside the fence grown by kTolerance_m, where up to
    // kMeasuredBelowFloor_m below the floor counts as on it — nothing flies through a floor, and an
    // estimate on GPS and barometer wanders by tenths of a metre (a v1.15 SITL: 0.1-0.3 m).
    static constexpr double kMeasuredBelowFloor_m = 0.5;
    bool holds_measured(const physics::Vec3& x) const;
    // x on the floor when it is measured below it.
    physics::Vec3 on_floor(const physics::Vec3& x) const;
};

struct PlanOptions {
    std::string formation = "single";
    physics::GridOptions grid;
    double min_separation_m = 0.3;
    Geofence fence;
    double check_dt_s = 0.01;
};

struct Violation {
    double t_s = 0;
    std::string what;  // one line: what, who, where, when
};

struct Plan {
    PlanOptions options;
    physics::Formation formation;
    physics::ReferenceTrajectory reference;
    std::vector<std::string> vehicles;  // v1..vK
    double duration_s() const { return reference.duration(); }
    // Vehicle i's setpoint at t.
    physics::Setpoint setpoint(std::size_t vehicle, double t) const;
};

// Throws dw::InputError for bad options (unknown formation, impossible altitudes, a separation
// outside kSeparationRange).
Plan make_plan(const PlanOptions& o);
// The first separation, geofence or non-finite-setpoint violation over the whole plan, if any.
// Every check must be positively satisfied (NaN fails them all). Throws dw::Stopped on `stop`.
std::optional<Violation> check(const Plan& p, const std::stop_token& stop = {});
// Fraction of the square's 10 cm cells that a vehicle's measured (constant-speed) path passes
// within 10 cm of.
double coverage(const Plan& p, const std::stop_token& stop = {});
// The plan as YAML (or JSON when `json`), for the record and for `dw-sim fly --plan`.
std::string to_document(const Plan& p, bool json);

}  // namespace dw::planner
