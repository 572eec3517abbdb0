#include "physics/vehicle.hpp"

#include <cmath>

namespace dw::physics {

double Rng::normal() {
    if (has_spare_) {
        has_spare_ = false;
        return spare_;
    }
    double u = 0, v = 0, s = 0;
    do {  // Marsaglia's polar method
        u = 2.0 * uniform() - 1.0;
        v = 2.0 * uniform() - 1.0;
        s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    const double k = std::sqrt(-2.0 * std::log(s) / s);
    spare_ = v * k;
    has_spare_ = true;
    return u * k;
}

double OrnsteinUhlenbeck::step(double dt, Rng& rng) {
    const double a = std::exp(-dt / tau_);
    x_ = a * x_ + sigma_ * std::sqrt(1.0 - a * a) * rng.normal();
    return x_;
}

SimVehicle::SimVehicle(const DynamicsParams& p, double gravity, const Vec3& start, Rng rng)
    : p_(p),
      g_(gravity),
      rng_(rng),
      wander_{OrnsteinUhlenbeck(p.hover_noise_m, p.hover_noise_time_s),
              OrnsteinUhlenbeck(p.hover_noise_m, p.hover_noise_time_s),
              OrnsteinUhlenbeck(p.hover_noise_m, p.hover_noise_time_s)} {
    state_.position = start;
}

void SimVehicle::step(const Setpoint& sp, double dt) {
    Vec3 error;
    for (int i = 0; i < 3; ++i) error[i] = wander_[static_cast<std::size_t>(i)].step(dt, rng_);
    const double w = p_.natural_frequency_rad_s;
    const Vec3 acc = w * w * (sp.position + error - state_.position) +
                     2.0 * p_.damping * w * (sp.velocity - state_.velocity) + sp.acceleration;
    state_.velocity += acc * dt;  // semi-implicit Euler
    state_.position += state_.velocity * dt;
    state_.acceleration = acc;
    // Thrust balances gravity and accelerates: its direction is the body's up axis (-z in FRD).
    const Vec3 thrust = acc - Vec3(0, 0, g_);
    const Vec3 body_down = -thrust.normalized();
    const Eigen::Quaterniond yaw(Eigen::AngleAxisd(sp.yaw_rad, Vec3::UnitZ()));
    const Eigen::Quaterniond tilt = Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), body_down);
    state_.orientation = (tilt * yaw).normalized();
}

}  // namespace dw::physics
