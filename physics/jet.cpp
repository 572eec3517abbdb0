#include "physics/jet.hpp"

#include <cmath>

namespace dw::physics {

Jet Jet::make(const VehicleParams& v, const PhysicsConfig& c) {
    Jet j;
    j.model = c.jet_model;
    j.thrust_n = v.mass_kg * c.gravity_m_s2;
    const double disc = static_cast<double>(v.rotors) * M_PI * v.prop_radius_m * v.prop_radius_m;
    j.u_hover = std::sqrt(j.thrust_n / (2.0 * c.air_density_kg_m3 * disc));
    j.l = v.motor_distance_m;
    j.inv_l = 1.0 / v.motor_distance_m;
    // Every jet carries its Bauersfeld width: merged columns (an effect that regroups jets) are Bauersfeld jets
    // whatever their members' model, and a zero width made them NaN.
    j.k = jet_coefficients(c, v);
    j.c_half = j.k.width * v.motor_distance_m;
    if (j.model == JetModelKind::bauersfeld) {
        j.k_centre = j.u_hover * j.k.strength;
    } else {
        j.k_centre = j.u_hover * c.jain.c_ax * c.jain.diameter_m;
        j.jain_z0 = c.jain.z0_m;
        j.jain_c_rad = c.jain.c_rad;
    }
    return j;
}

double Jet::centreline(double s) const {
    if (s <= 0) return 0;
    if (model == JetModelKind::bauersfeld) return k_centre / (s * inv_l + k.origin);
    return k_centre / std::max(s - jain_z0, 0.05);
}

double Jet::half_width(double s) const {
    if (model == JetModelKind::bauersfeld) return c_half * (std::max(s, 0.0) * inv_l + k.origin);
    return std::max(s - jain_z0, 0.05) * std::sqrt(std::log(2.0) / jain_c_rad);
}

double Jet::axial(double r, double s) const {
    if (s <= 0) return 0;
    if (model == JetModelKind::bauersfeld) {
        const double eta = r / half_width(s);
        const double d = 1.0 + kProfileB * eta * eta;
        return centreline(s) / (d * d);
    }
    const double z = std::max(s - jain_z0, 0.05);
    return centreline(s) * std::exp(-jain_c_rad * (r / z) * (r / z));
}

double Jet::radial(double r, double s) const {
    if (s <= 0 || model != JetModelKind::bauersfeld) return 0;
    const double eta = r / half_width(s);
    const double d = 1.0 + kProfileB * eta * eta;
    return centreline(s) * k.width * eta * (1.0 / (d * d) - 0.5 / d);
}

double Jet::momentum_flux(double rho) const {
    const double uc_rh = k_centre * c_half;  // U_c * r_half is independent of s
    return rho * kMomentumIntegral * uc_rh * uc_rh;
}

double Jet::transport_delay(double s) const {
    if (s <= 0) return 0;
    if (model == JetModelKind::bauersfeld) {
        return descent_numerator(s) / descent_speed();
    }
    // ∫ dz (z - z0) / k for the Jain form (z - z0 clamped at 0.05 m near the pole).
    const double z = std::max(s - jain_z0, 0.05);
    return 0.5 * z * z / k_centre;
}

}  // namespace dw::physics
