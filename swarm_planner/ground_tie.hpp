#pragma once
// Tying a PX4 local frame to the lab's floor from PX4's own estimate (px4_config.hpp, `ground:
// estimate`). A PX4 on its own sensors puts its local origin where its GPS and barometer say, metres
// off the floor (a real v1.15 SITL: 1.7-2.8 m, different at every boot). On the ground, still, its
// estimate's D is the floor's: the tie is the median D over the latest window in which the estimate
// stays within kGroundSteady_m and barely moves, taken only while PX4 reports the vehicle disarmed
// and kept, frozen, from the arming on (the estimate drifts while it waits: the latest window is the
// one closest to the take-off). The mocap bridge (poses) and the planner's link (commands) each tie
// from the same estimate by this one rule, so their frames agree; the link arms nothing untied.
#include <deque>
#include <optional>
#include <string>

#include "physics/vehicle.hpp"

namespace dw::planner {

// An estimator on GPS and barometer wanders on the ground: a v1.15 SITL's EKF2 moved its D by 0.09-0.24 m
// and its velocity up to 0.45 m/s within 2 s, standing still. The tie takes the median of what a
// still vehicle's estimate does; a vehicle that climbs or is carried moves farther.
inline constexpr double kGroundWindow_s = 2.0;   // the estimate watched this long
inline constexpr double kGroundSteady_m = 0.3;   // its D within this over the window
inline constexpr double kGroundStill_mps = 0.6;  // and its speed below this
inline constexpr std::size_t kGroundMinSamples = 20;

class GroundTie {
public:
    // One estimate (PX4's local NED) at t seconds; `on_ground`: PX4 says it is disarmed.
    void add(double t_s, const physics::Vec3& local, const physics::Vec3& velocity, bool on_ground);
    bool tied() const { return floor_d_.has_value(); }
    // The floor's D in PX4's local frame, once tied (frozen while the vehicle is armed).
    std::optional<double> floor_d() const { return floor_d_; }
    // Why it is not tied yet, or what it tied: one line.
    std::string describe() const;

private:
    struct Sample {
        double t, d, speed;
    };
    std::deque<Sample> window_;
    std::optional<double> floor_d_;
    double spread_ = 0, fastest_ = 0;  // the last full window's, for describe()
    bool judged_ = false;              // a full window has been judged
};

}  // namespace dw::planner
