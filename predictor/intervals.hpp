#pragma once
// Prediction intervals from the explainer's noise model (analysis/noise.cpp, excess_of): about a
// right prediction p, a recorded wrench scatters per axis with variance
//     floor² + (2 I p)²
// — the flight's own noise floor (the recorded wrench's spread where nobody is near, each neighbour
// beyond its near radius, physics/bodies.hpp: the residual's slow error and its jitter) and the
// jets' turbulence, whose force fluctuation grows with the push (I: the physics' turbulence
// intensity, which dw-explain calibrate measures, as it does each vehicle class's floor). The 95 %
// interval is p ± kZ95 σ (core/stats.hpp); its coverage on held-out samples says whether the model
// and the noise model hold.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "core/stats.hpp"
#include "physics/bodies.hpp"
#include "predictor/dataset.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

// The physics' turbulence intensity where its turbulence is on, else 0.
inline double turbulence_intensity(const physics::PhysicsConfig& p) {
    return p.turbulence.enabled ? p.turbulence.intensity : 0;
}

struct NoiseModel {
    double intensity = 0;                             // I (0: no turbulence term)
    std::map<std::string, flight::AxisValues> floor;  // per flight (Source::name), per axis (NaN: unknown)
    // The flights with fewer than kMinFarSamples samples with nobody near: their floor is their
    // sufferer class's — the physics' (VehicleClass::noise_floor_n, calibrated), else the median of
    // the known floors of this dataset's flights of that class — or, where there is none, the jitter
    // of their whole recording (successive differences, as the explainer's when nobody is ever far),
    // which leaves out the residual's slow error: those intervals are too narrow, not too wide.
    std::vector<std::string> from_class, from_differences;
};
// Each flight's floor from its samples with nobody near (all of them, held out or not: a lab
// measures its noise with nobody near, and no sample near a jet enters it), else (below).
NoiseModel noise_model(const Dataset& all, const physics::PhysicsConfig& physics);

// kZ95 sqrt(floor² + (2 I p)²): the 95 % interval's half width about prediction p.
double interval_half_width(double floor, double intensity, double p);
// ... online, on f_d, for a sufferer of parameters `sufferer` under `physics`: its vehicle class's
// calibrated floor (VehicleClass::noise_floor_n) and the physics' turbulence; 0 (none) when the
// class has no floor.
double f_d_half_width(const physics::PhysicsConfig& physics, const physics::VehicleParams& sufferer, double p);

// The 95 % interval's half width about prediction p on `axis` of a sample of flight `source` (NaN
// when that flight's floor is unknown).
double half_width(const NoiseModel& m, const std::string& source, std::size_t axis, double p);

// The share of the samples of `d` whose recorded `axis` lies inside the model's 95 % interval
// (their flights' floors from the noise model); NaN when no sample can say.
double coverage(const ForceModel& model, const Dataset& d, const NoiseModel& noise, std::size_t axis = kFdAxis);

}  // namespace dw::predictor
