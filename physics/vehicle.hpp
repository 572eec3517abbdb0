#pragma once
// Simulated vehicles that follow position/velocity setpoints with realistic lag, overshoot and
// hover noise, plus the random processes the simulator uses.
#include <cmath>
#include <Eigen/Geometry>
#include <cstdint>
#include <random>

#include "physics/config.hpp"
#include "physics/plausible.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics {

// Deterministic randomness: the same seed gives the same numbers on every machine.
class Rng {
public:
    explicit Rng(std::uint64_t seed) : engine_(seed) {}
    double uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }  // [0, 1)
    double normal();
    Rng split() { return Rng(engine_()); }

private:
    std::mt19937_64 engine_;
    bool has_spare_ = false;
    double spare_ = 0;
};

// Ornstein-Uhlenbeck process with stationary standard deviation sigma and time constant tau,
// stepped exactly (no discretisation error at any dt).
class OrnsteinUhlenbeck {
public:
    OrnsteinUhlenbeck(double sigma, double tau) : sigma_(sigma), tau_(tau) {}
    double step(double dt, Rng& rng);
    double value() const { return x_; }

private:
    double sigma_, tau_;
    double x_ = 0;
};

struct Setpoint {
    Vec3 position = Vec3::Zero();
    Vec3 velocity = Vec3::Zero();
    Vec3 acceleration = Vec3::Zero();
    double yaw_rad = 0;
};

// Every component finite: what may drive a vehicle, simulated or real.
inline bool is_finite(const Setpoint& sp) {
    return sp.position.allFinite() && sp.velocity.allFinite() && sp.acceleration.allFinite() &&
           std::isfinite(sp.yaw_rad);
}

struct VehicleState {
    Vec3 position = Vec3::Zero();
    Vec3 velocity = Vec3::Zero();
    Vec3 acceleration = Vec3::Zero();
    Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // body (FRD) -> world (NED)
};

class SimVehicle {
public:
    SimVehicle(const DynamicsParams& p, double gravity, const Vec3& start, Rng rng);
    // Second-order tracking of the setpoint (natural frequency, damping: lag and overshoot) with
    // a slowly wandering position error (hover noise); attitude follows the thrust direction.
    void step(const Setpoint& sp, double dt);
    const VehicleState& state() const { return state_; }
    // Where its air goes: the body's down axis in the world.
    Vec3 jet_axis() const { return state_.orientation * Vec3::UnitZ(); }

private:
    DynamicsParams p_;
    double g_;
    VehicleState state_;
    Rng rng_;
    std::array<OrnsteinUhlenbeck, 3> wander_;
};

}  // namespace dw::physics
