#pragma once
// Resimulating a recorded flight (not `dw-recorder replay`, which plays an MCAP file back onto DDS): the physics evaluated along the recorded poses (the neighbours'
// positions, velocities and attitudes from poses.csv, the sufferer's pose at every sample — it may
// fly), with each body's parameters from meta.json, then seen the way the recording sees it —
// sensor lag, clock offset, force scale, cell crosstalk, the tare — at the recorded wrench stamps.
// A flying sufferer (wrench_source residual) also feels its own drag and the ground effect when
// those effects are on. Reads only the flight folder's contract files.
//
// The air's wrench is evaluated once per configuration of the flow's effects on a uniform grid
// of mocap time (cached), so fitting the recording-side effects (time shifts, lag, scale,
// crosstalk) costs no new physics.
#include <array>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "physics/bodies.hpp"
#include "physics/config.hpp"
#include "physics/recording_chain.hpp"
#include "physics/wrench_model.hpp"

namespace dw::analysis {

using flight::Wrench6;

class Resimulation {
public:
    // Throws dw::InputError if the sufferer or a neighbour of meta.json has no poses, or a body's
    // parameters (meta.json, else `physics`) are unusable.
    explicit Resimulation(const flight::Flight& f, const physics::PhysicsConfig& physics = {}, double grid_hz = 100.0);

    // The wrench the recording would hold under physics c, at every wrench stamp. The stand's
    // own sample-and-hold is included: a wrench frame combines chip 0's fresh conversion with the
    // other seven chips' latest ones, on average half a conversion period old
    // (physics::StampSampler).
    std::vector<Wrench6> recorded(const physics::PhysicsConfig& c) const;
    // The air's wrench on the sufferer on the grid (mocap time), for the flow part of c.
    const std::vector<Wrench6>& air(const physics::PhysicsConfig& c) const;
    // At every wrench stamp, the standard deviation per axis of the lateral buffeting c's
    // turbulence gives (zero without turbulence): noise the mean flow cannot predict.
    std::vector<Wrench6> buffeting_sigma(const physics::PhysicsConfig& c) const;
    // At every wrench stamp, how much of the push is shared: 1 − the strongest neighbour's share of
    // the sum of each neighbour's push alone (the norm of its force), 0 with one jet or none.
    std::vector<double> shared_push(const physics::PhysicsConfig& c) const;

    const std::vector<double>& stamps() const { return stamps_; }       // wrench.csv t
    const std::vector<Wrench6>& measured() const { return measured_; }  // wrench.csv values
    double grid_t0() const { return t0_; }
    double grid_dt() const { return dt_; }
    std::size_t grid_size() const { return n_; }
    int neighbours() const { return static_cast<int>(bodies_.neighbours.size()); }
    // Neighbour j's recorded position and velocity at mocap time t.
    std::array<double, 3> position(int j, double t) const;
    std::array<double, 3> velocity(int j, double t) const;
    std::array<double, 3> sufferer(double t) const;
    std::array<double, 3> sufferer_velocity(double t) const;
    double near_radius(int j) const { return near_radius_[static_cast<std::size_t>(j)]; }
    // Which wrench columns carry a measurement (a residual source may not measure moments).
    const std::array<bool, 6>& measured_axes() const { return measured_axes_; }
    bool flying() const { return flying_; }  // no load stand: the sufferer flies
    // How many of the recording's first samples a stand's tare averages (0: no tare here — a
    // residual source is tared by its importer).
    std::size_t tare_samples(const physics::PhysicsConfig& c) const;
    // How long a tare the recording had: a stand's tare_s, none for a residual source.
    double tare_s(const physics::PhysicsConfig& c) const;

private:
    // c's flow part (what the air does) with the sufferer's own parameters; the neighbours' jets in it.
    physics::PhysicsConfig flow_of(const physics::PhysicsConfig& c) const;
    std::vector<physics::Jet> jets_of(const physics::PhysicsConfig& flow) const;
    // The producers at grid point i (positions less `offset`) and the sufferer's position there.
    physics::Vec3 producers_at(std::size_t i, const physics::WrenchModel& model, const std::vector<physics::Jet>& jets,
                               const physics::Vec3& offset, std::vector<physics::Producer>& ps) const;
    bool near(const physics::Vec3& sufferer, const std::vector<physics::Producer>& ps) const;
    // f(k, the sufferer, the model, the producers) at every wrench stamp k, for c's flow (no
    // position error: where the neighbours were recorded).
    using AtStamp = std::function<void(std::size_t, const physics::Vec3&, const physics::WrenchModel&,
                                       const std::vector<physics::Producer>&)>;
    void at_stamps(const physics::PhysicsConfig& c, const AtStamp& f) const;
    struct GridState {  // the recorded states at one grid time
        std::array<double, 3> sufferer;
        std::array<double, 3> sufferer_velocity;
        std::vector<std::array<double, 9>> neighbours;  // position, velocity, jet axis
    };
    flight::BodyTracks bodies_;
    std::vector<GridState> grid_;
    physics::VehicleParams sufferer_params_;
    std::vector<physics::VehicleParams> neighbour_params_;
    std::vector<double> near_radius_;
    std::array<bool, 6> measured_axes_{true, true, true, true, true, true};
    bool flying_ = false;
    bool residual_ = false;
    std::vector<double> stamps_;
    std::vector<Wrench6> measured_;
    double t0_ = 0, dt_ = 0.01;
    std::size_t n_ = 0;
    mutable std::map<KeyValues, std::vector<Wrench6>> cache_;  // by the flow's values (physics::key_values)
    mutable std::vector<KeyValues> cache_order_;
};

// Where each wrench sample is, relative to the formation.
struct SampleInfo {
    int leg = -1;                  // -1: not in a block (a measurement leg, an encounter, a stretch of time)
    int direction = 0;             // of travel along E on legs: +1, -1, 0 (below 0.1 m/s; always 0 off legs)
    double n = 0, e = 0, h = 0;    // the neighbours' centroid N, E; the lowest one's height above the sufferer
    double offset = 0, above = 0;  // the horizontally nearest neighbour: horizontal offset, height above the sufferer
    double speed = 0;
    double leg_fraction = 0;  // 0..1 through the leg
    bool near = false;        // a neighbour within its near radius horizontally (physics/bodies.hpp)
    double shared = 0;        // Resimulation::shared_push: 0 where one jet pushes, up to 1 − 1/K where K share it
};
std::vector<SampleInfo> describe(const Resimulation& r, const flight::Blocks& blocks);
// describe() with each sample's shared push under physics c (Resimulation::shared_push) filled in.
std::vector<SampleInfo> describe(const Resimulation& r, const flight::Blocks& blocks, const physics::PhysicsConfig& c);

// The vertical-separation bands residuals are located and drawn in.
struct Band {
    double lo, hi;
    const char* name;
};
inline constexpr std::array<Band, 3> kBands{
    {{0.0, 0.55, "0.0-0.55 m"}, {0.55, 1.05, "0.55-1.05 m"}, {1.05, 1.5, "1.05-1.5 m"}}};
inline int band_index(double h) { return h < kBands[1].lo ? 0 : (h < kBands[2].lo ? 1 : 2); }

}  // namespace dw::analysis
