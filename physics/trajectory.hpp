#pragma once
// Formations (the study's defaults) and the built-in grid-leg generator: the formation's reference
// point flies straight legs along E at constant speed over a square centred on the stand,
// alternating +E/-E, at chosen relative altitudes, with smooth acceleration into and out of each
// leg and minimum-jerk transitions between legs. (The planner, issue 7, replaces this with
// `--plan FILE`.)
#include <string>
#include <vector>

#include "core/numbers.hpp"
#include "physics/vehicle.hpp"

namespace dw::physics {

struct Formation {
    std::string name;           // as on the command line: single, side_by_side, leader_follower, ...
    std::string meta_name;      // as in meta.json (leader_follower3 -> leader_follower)
    std::vector<Vec3> offsets;  // each vehicle's offset from the reference point, NED [m]
};

// Throws dw::InputError for an unknown name.
Formation make_formation(const std::string& name);
const std::vector<std::string>& formation_names();

// What the grid generator accepts (the planner narrows the altitude to its geofence).
inline constexpr Range kAltitudeRange{0.05, 3.0, "m"};
inline constexpr Range kSpeedRange{0.05, 3.0, "m/s"};
inline constexpr Range kLegsRange{1, 1000};

struct GridOptions {
    std::vector<double> altitudes_m{0.3, 0.8, 1.3};  // reference point above the sufferer
    int legs = 36;
    double half_width_m = 1.0;      // the square is 2 x half_width on a side
    std::vector<double> lines_n_m;  // explicit N of the legs at each altitude (default: spread over the square)
    double speed_mps = 0.5;
    double ramp_s = 1.2;         // smooth acceleration into and out of each leg
    double hover_s = 0.5;        // pause after each leg and each transition
    double start_hover_s = 3.0;  // at the first leg's start, far from the stand (the tare)
    double stand_height_m = 1.4;
};

struct LegInfo {
    int index = 0;
    double n_m = 0;                 // the leg's N coordinate
    double altitude_m = 0;          // relative to the sufferer
    int direction = 1;              // +1: towards +E, -1: towards -E
    double t_start = 0, t_end = 0;  // the constant-speed segment over the square
};

class ReferenceTrajectory {
public:
    // Throws dw::InputError for impossible options.
    explicit ReferenceTrajectory(const GridOptions& o);
    Setpoint at(double t) const;
    double duration() const { return duration_; }
    const std::vector<LegInfo>& legs() const { return legs_; }

private:
    enum class Kind { hold, min_jerk, ramp_up, cruise, ramp_down };
    struct Segment {
        Kind kind;
        double t0, length_s;
        Vec3 p0, dir;         // unit direction of motion
        double distance = 0;  // min_jerk
        double speed = 0;     // ramps and cruise
    };
    void add(Kind kind, double length_s, const Vec3& p0, const Vec3& p1, double speed);

    std::vector<Segment> segments_;
    std::vector<LegInfo> legs_;
    double duration_ = 0;
};

}  // namespace dw::physics
