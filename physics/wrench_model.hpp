#pragma once
// The wrench the downwash of K producers exerts on the sufferer.
//
// The sufferer's planform (rotor discs, arms, body) is split into cells; each cell gets bluff-body
// drag from the air velocity there — f_d = ½ rho C_d A |u_d| u_d vertically and ½ rho C_lat A |u_h| u_h
// laterally — and torques r x f about the sufferer's centre. Spinning rotors also lose thrust in
// oncoming flow, ΔT ≈ k_v Ω v_in per rotor (PHYSICS.md). Several producers aggregate by a force sum
// or by velocity superposition. The flow effects that are on act here through their hooks
// (physics/effect_types.hpp, stage air): a wrench of their own, the jets' transport delay, or the
// jets regrouped (jets that merge).
#include <Eigen/Core>
#include <array>
#include <span>
#include <vector>

#include "physics/config.hpp"
#include "physics/effect_types.hpp"
#include "physics/jet.hpp"

namespace dw::physics {

using Vec3 = Eigen::Vector3d;
// Where the load stand holds the sufferer, lab NED: above the origin, at the stand's height.
inline Vec3 sufferer_on_stand(const StandParams& s) { return Vec3(0, 0, -s.height_m); }
// f_n, f_e, f_d [N]; m_roll, m_pitch, m_yaw [N·m] — NED axes of the (level) sufferer.
using Wrench = Eigen::Matrix<double, 6, 1>;
// The same six numbers as the flight folder and the recording chain hold them (flight::Wrench6).
inline Wrench to_wrench(const flight::Wrench6& w) { return Eigen::Map<const Wrench>(w.data()); }
inline flight::Wrench6 to_wrench6(const Wrench& w) {
    flight::Wrench6 out;
    Eigen::Map<Wrench>(out.data()) = w;
    return out;
}

struct Producer {
    Vec3 position = Vec3::Zero();  // world NED [m]
    Vec3 axis{0, 0, 1};            // unit vector along which its air goes (world NED; down when level)
    Vec3 velocity = Vec3::Zero();  // world NED [m/s]
    Jet jet;
    double gust = 1.0;                 // turbulence: multiplier on the jet speed
    Vec3 lateral_gust = Vec3::Zero();  // lateral buffeting: velocity across the axis / axial speed
};

// The air at the sufferer as a flow effect sees it: where the sufferer is, and the jets.
struct AirScene {
    Vec3 sufferer;
    std::span<const Producer> producers;
};
// A jet and the weight its air has in the aggregate (an effect that regroups jets).
struct WeightedProducer {
    Producer producer;
    double weight = 1;
};

// The sufferer's planform cells, in its own level frame centred on it (x north, y east).
struct Planform {
    std::vector<double> x, y, area;
    // Each rotor's disc cells, [first, last): contiguous, so drag() sums a disc's inflow without a
    // scatter (a store and reload per cell cost drag() a third of its time).
    std::vector<std::array<std::size_t, 2>> rotor_cells;
    std::vector<std::array<double, 2>> rotor_centre;
    std::vector<double> rotor_area;
    std::size_t size() const { return x.size(); }
    static Planform make(const SuffererParams& s);
};

class WrenchModel {
public:
    explicit WrenchModel(const PhysicsConfig& config);

    Wrench evaluate(const Vec3& sufferer, std::span<const Producer> producers) const;
    // The standard deviation, per axis, of the lateral buffeting `evaluate` adds when each
    // producer's lateral gust has `intensity` per horizontal axis (independent across producers).
    Wrench buffeting_sigma(const Vec3& sufferer, std::span<const Producer> producers, double intensity) const;
    // The air velocity (world NED) at a point, summed over producers (velocity superposition).
    Vec3 air_velocity(const Vec3& point, std::span<const Producer> producers) const;

    // A producer with the neighbours' parameters, level, at `position`.
    Producer producer(const Vec3& position, const Vec3& velocity = Vec3::Zero()) const;
    const Planform& planform() const { return planform_; }
    const PhysicsConfig& config() const { return config_; }
    const Jet& neighbour_jet() const { return neighbour_jet_; }

private:
    struct Scratch;
    // Adds weight x the producer's air velocity at base + (x[i], y[i], 0) for i < n.
    void add_velocity(const Vec3& base, const double* x, const double* y, std::size_t n, const Producer& p,
                      double weight, double* ux, double* uy, double* uz) const;
    // The same for a Jain jet (cell by cell; the Bauersfeld loop above takes two cells at once).
    void add_velocity_jain(const Vec3& base, const double* x, const double* y, std::size_t n, const Producer& p,
                           double weight, double delay_scale, double* ux, double* uy, double* uz) const;
    void add_velocity(const Vec3& sufferer, const Producer& p, double weight, Scratch& s) const;
    Wrench drag(Scratch& s) const;  // s: the air at each cell, and room for each cell's force
    Wrench buffeting(const Vec3& sufferer, std::span<const Producer> producers) const;
    // The flow effects' own wrenches and the buffeting.
    Wrench beyond_the_jets(const Vec3& sufferer, std::span<const Producer> producers) const;

    PhysicsConfig config_;
    std::vector<const EffectType*> air_effects_;  // the flow effects on, in the vocabulary's order
    const EffectType* regrouper_ = nullptr;       // the first of them that regroups the jets
    double delay_scale_ = 0;                      // the jets' transport delay (the first that sets one)
    Planform planform_;
    Jet neighbour_jet_;
    double half_rho_cd_ = 0;
    double half_rho_clat_ = 0;
};

}  // namespace dw::physics
