#pragma once
// Prediction intervals from the noise model (physics/prediction_noise.hpp): about a right
// prediction p, a recorded wrench scatters per axis with variance
//     floor² + (s p)² + (tau dp/dt)²
// — the flight's own noise floor (the recorded wrench's spread where the physics predicts no push:
// nobody near, a neighbour below or beside its jet), a scatter that grows with the push and one that
// grows with how fast it changes (s, tau: the physics' calibrated noise model, else 2 I and none).
// The 95 % interval is p ± kZ95 σ (core/stats.hpp); its coverage on held-out samples says whether
// the model and the noise model hold.
#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "core/stats.hpp"
#include "physics/bodies.hpp"
#include "physics/prediction_noise.hpp"
#include "predictor/dataset.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

struct NoiseModel {
    physics::PredictionNoise noise;                   // s, tau
    std::map<std::string, flight::AxisValues> floor;  // per flight (Source::name), per axis (NaN: unknown)
    // The flights with fewer than kMinFarSamples quiet samples: their floor is their
    // sufferer class's — the physics' (VehicleClass::noise_floor_n, calibrated), else the median of
    // the known floors of this dataset's flights of that class — or, where there is none, the jitter
    // of their whole recording (successive differences, as the explainer's when nobody is ever far),
    // which leaves out the residual's slow error: those intervals are too narrow, not too wide.
    std::vector<std::string> from_class, from_differences;
};
// Each flight's floor from its quiet samples — nobody near, or the physics predicting a push under
// physics::kQuietPush_n — (all of them, held out or not: a lab measures its noise where no jet
// reaches, and no sample a jet reaches enters it), else (below).
NoiseModel noise_model(const Dataset& all, const physics::PhysicsConfig& physics);

// kZ95 σ: the 95 % interval's half width about prediction p changing at p_rate [N/s].
double interval_half_width(double floor, const physics::PredictionNoise& n, double p, double p_rate);
// ... online, on f_d, for a sufferer of parameters `sufferer` under `physics`: its vehicle class's
// calibrated floor (VehicleClass::noise_floor_n) and the physics' noise model; 0 (none) when the
// class has no floor.
double f_d_half_width(const physics::PhysicsConfig& physics, const physics::VehicleParams& sufferer, double p,
                      double p_rate);

// The 95 % interval's half width about prediction p on `axis` of a sample of flight `source` (NaN
// when that flight's floor is unknown).
double half_width(const NoiseModel& m, const std::string& source, std::size_t axis, double p, double p_rate);

// The share of the samples of `d` whose recorded `axis` lies inside the model's 95 % interval
// (their flights' floors from the noise model); NaN when no sample can say.
double coverage(const ForceModel& model, const Dataset& d, const NoiseModel& noise, std::size_t axis = kFdAxis);

}  // namespace dw::predictor
