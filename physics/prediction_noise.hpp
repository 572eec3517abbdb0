#pragma once
// The noise model of a prediction (issue 71): about a right prediction p, a recorded force scatters
// with standard deviation
//     sigma = sqrt(floor² + (s p)² + (tau dp/dt)²)
// — the flight's own floor (its recorded force's spread where the physics predicts no push), a
// scatter that grows with the push (s: the jets' turbulence, 2 I, and what the mean-flow model
// leaves near a jet) and one that grows with how fast the push changes (tau: when a wake arrives
// varies — its transport, each flight's clocks). One model for the explainer's calibration, the
// predictor's intervals and the online node's.
#include <cmath>
#include <cstddef>
#include <span>
#include <vector>

#include "physics/config.hpp"

namespace dw::physics {

// A sample whose predicted push is below this is quiet: what is recorded there is the flight's floor.
inline constexpr double kQuietPush_n = 0.001;
// Whether a sample with a neighbour near is quiet all the same (one below, or beside its jet): the
// push predicted there is under kQuietPush_n. (With nobody near, every sample is.)
inline bool quiet_push(double predicted_push) { return std::abs(predicted_push) < kQuietPush_n; }
// dp/dt is the push's change over ± this (the wrench's samples either side; a gap wider than it
// leaves the rate of that side out).
inline constexpr double kRateHalfSpan_s = 0.05;

// The physics' turbulence intensity where its turbulence is on, else 0.
inline double turbulence_of(const PhysicsConfig& p) { return p.turbulence.enabled ? p.turbulence.intensity : 0.0; }

// A jet whose speed fluctuates by the turbulence intensity I scatters its push p by 2 I p (the
// force goes as the speed squared): the push share turbulence alone gives, per unit of intensity.
inline constexpr double kPushSharePerIntensity = 2;

// The configuration's calibrated noise model, else (push_share 0) 2 I and no timing term.
PredictionNoise prediction_noise_of(const PhysicsConfig& p);
// The turbulence intensity a noise model counts near a jet: its push share over 2.
inline double counted_intensity(const PredictionNoise& n) { return n.push_share / kPushSharePerIntensity; }

double prediction_sd(double floor, const PredictionNoise& n, double p, double p_rate);

// dp/dt at every sample of one series (times t ascending, pushes p): the difference across
// ± kRateHalfSpan_s (one-sided at the ends or beside a gap; 0 for a sample alone).
std::vector<double> push_rates(std::span<const double> t, std::span<const double> p);

// The same online: each new prediction's rate from the oldest kept within 2 kRateHalfSpan_s before it.
class PushRate {
public:
    double update(double t, double p);

private:
    std::vector<std::pair<double, double>> recent_;  // (t, p), oldest first, within the span
};

// One sample's share of the fit below: its residual (recorded - predicted), floor, push and rate.
struct NoiseSample {
    double residual = 0, floor = 0, p = 0, p_rate = 0;
};
// The push share and timing spread that maximise the Gaussian likelihood of the residuals
// (coordinate-wise golden-section searches within kPushShareRange and kTimingSpreadRange_s).
PredictionNoise fit_prediction_noise(std::span<const NoiseSample> samples);

}  // namespace dw::physics
