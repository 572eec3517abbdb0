#pragma once
// What a value from a wire (a DDS sample, a NatNet packet, PX4's odometry, a recording) can be as a
// measurement in the lab: one place for each rule, used wherever such values enter.
#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>

namespace dw::physics {

// What a measured pose or velocity in the lab's frame can be: no lab room is larger, no multirotor
// over a stand faster. Beyond them a value from a wire is garbage (Motive sends ±3.4e38 when its
// solver is confused; 1e39 m is finite as a double but +inf as PX4's float).
inline constexpr double kMaxPlausiblePositionM = 100.0;
inline constexpr double kMaxPlausibleSpeedMps = 50.0;
// A position from a wire that can be a measurement: finite and within kMaxPlausiblePositionM.
inline bool plausible_position(const Eigen::Vector3d& x) {
    return x.allFinite() && x.cwiseAbs().maxCoeff() <= kMaxPlausiblePositionM;
}
// A quaternion from a wire that can be an orientation: finite and far enough from zero to be
// normalised (a unit quaternion sent as floats, or a slightly damaged one, passes). Any order.
inline constexpr double kMinQuaternionNorm = 0.5;
inline bool plausible_orientation(const Eigen::Vector4d& q) { return q.allFinite() && q.norm() > kMinQuaternionNorm; }
// What a load stand under multirotors can measure: no vehicle over it pushes harder or twists more.
// Beyond them a wrench from a wire is garbage (a garbled word reads 1e300).
inline constexpr double kMaxPlausibleForceN = 1000.0;
inline constexpr double kMaxPlausibleTorqueNm = 1000.0;
// f_n f_e f_d m_roll m_pitch m_yaw
inline bool plausible_wrench(const std::array<double, 6>& w) {
    for (std::size_t k = 0; k < 6; ++k)
        if (!(std::abs(w[k]) <= (k < 3 ? kMaxPlausibleForceN : kMaxPlausibleTorqueNm))) return false;
    return true;
}

}  // namespace dw::physics
