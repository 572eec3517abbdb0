#pragma once
// A single producer's downwash jet.
//
// Bauersfeld et al., "Modeling of the Downwash of Multirotors" (RA-L 2025, arXiv 2403.13321):
// a far-wake turbulent round jet needing only mass, propeller radius and size. With s the
// distance below the producer along its thrust axis, r the distance from that axis, l the
// diagonal motor distance and n_p rotors of radius R_p:
//   U_H       = sqrt(m g / (2 rho n_p pi R_p^2))         hover induced velocity
//   U_c(s)    = U_H * 10.11 / (s/l + 5.817)               centreline speed
//   r_half(s) = 0.07668 * (s/l + 5.817) * l               half-width
//   U(r, s)   = U_c / (1 + (sqrt(2) - 1) (r / r_half)^2)^2
// (public implementations multiply by n_p and divide r_half by l twice: bugs, not used here).
// The radial (entrainment) velocity follows from continuity for this profile:
//   V(r, s) = U_c * 0.07668 * eta * (f(eta) - 1 / (2 (1 + b eta^2))),  eta = r/r_half, b = sqrt(2)-1
// (outward near the axis, inward outside it).
//
// Jain et al. (ICUAS 2019) Gaussian alternative: V = v_i C_ax D / (s - z0) exp(-C_rad (r/(s - z0))^2),
// with constants to be fitted; s - z0 is kept above 0.05 m where the form has a pole.
#include "physics/config.hpp"

namespace dw::physics {

inline constexpr double kProfileB = 0.41421356237309515;  // sqrt(2) - 1
inline constexpr double kMomentumIntegral = 2.528;        // ∫U² dA = 2.528 U_c² r_half²

// Per-producer constants of its jet, computed once.
struct Jet {
    JetModelKind model = JetModelKind::bauersfeld;
    double u_hover = 0;   // U_H [m/s]
    double thrust_n = 0;  // m g
    double inv_l = 0;     // 1 / l
    double l = 0;
    JetCoefficients k;    // Bauersfeld: the vehicle's class's, else the configuration's
    double k_centre = 0;  // Bauersfeld: U_H * strength; Jain: v_i * C_ax * D
    double c_half = 0;    // Bauersfeld: width * l
    double jain_z0 = 0;
    double jain_c_rad = 0;

    static Jet make(const VehicleParams& v, const PhysicsConfig& c);

    double centreline(double s) const;        // U_c(s) [m/s], 0 above the producer
    double half_width(double s) const;        // r_half(s) [m]
    double axial(double r, double s) const;   // U(r, s) [m/s]
    double radial(double r, double s) const;  // V(r, s) [m/s], outward positive
    // ρ ∫U² dA from the closed form [N]; independent of s for the Bauersfeld jet.
    double momentum_flux(double rho) const;
    // Time for the wake to descend s: ∫0^s dz / U_c(z) = (s²/(2l) + origin s) / (strength U_H) [s].
    double transport_delay(double s) const;
    // Bauersfeld: that time's numerator, s²/(2l) + origin s [m], and denominator, strength U_H [m/s]
    // (inline: the physics' inner loop).
    double descent_numerator(double s) const { return s * s * 0.5 * inv_l + k.origin * s; }
    double descent_speed() const { return k.strength * u_hover; }
};

}  // namespace dw::physics
