#pragma once
// The explainer's fitting layer: the data every stage reads, one effect's fit with Ceres, and the
// model the candidates are scored against.
//
// Where the time goes: a flight's prediction under one set of parameters is a resimulation of the whole
// flight (Resimulation::recorded: for a flow effect the physics along every recorded pose, for a
// recording-side effect the sensor chain over the cached air). Ceres asks for one residual row at
// a time, so Fit keeps the last kPredictionCache predictions: the P + 1 resimulations of a forward-
// difference Jacobian are paid once and shared by every row. ExplainData::resimulations counts them.
#include <cstddef>
#include <utility>
#include <vector>

#include "analysis/effects.hpp"
#include "analysis/resimulation.hpp"
#include "physics/config.hpp"

namespace dw::analysis {

using flight::AxisValues;

// Everything a fit needs: the data, which samples, the axes' scales.
struct ExplainData {
    const Resimulation& sim;
    const std::vector<SampleInfo>& info;
    AxisValues sigma;
    std::vector<std::size_t> on_legs;       // sample indices on measurement legs
    std::vector<Wrench6> buffeting;         // per sample: the lateral buffeting's standard deviation
    std::size_t legs = 0;                   // blocks that hold samples
    double huber_delta = 3;                 // noise floors: beyond it a residual counts linearly in the fits
    mutable std::size_t resimulations = 0;  // predictions of the whole flight paid so far (see above)

    // The flight as the recording sees it under physics c: one resimulation, counted.
    std::vector<Wrench6> predict(const physics::PhysicsConfig& c) const;
};

// The data of a flight's fits: its resimulation, its samples' bookkeeping, its noise floor.
// Throws dw::InputError when fewer blocks than `folds` hold wrench samples.
ExplainData explain_data(const Resimulation& sim, const std::vector<SampleInfo>& info, const flight::Blocks& blocks,
                         int folds, double huber_delta, const physics::PhysicsConfig& physics, const AxisValues& sigma);

// Sample i's squared residual on axis a in noise floors (0 on an axis that carries no measurement).
double norm_sq(const ExplainData& d, const std::vector<Wrench6>& pred, std::size_t i, std::size_t a);
// Per axis, the residual's RMS over the samples on legs (N or N·m; 0 on an axis not measured).
AxisValues residual_rms(const ExplainData& d, const std::vector<Wrench6>& pred);
// The sum of norm_sq over the samples on legs and every axis.
double rss(const ExplainData& d, const std::vector<Wrench6>& pred);

// A fit of one effect's parameters with the rest of the model fixed.
class Fit {
public:
    Fit(const ExplainData& d, const physics::PhysicsConfig& base, const Effect& e) : d_(d), base_(base), e_(e) {}

    // The flight predicted with the effect at values v (from the cache when it holds v).
    const std::vector<Wrench6>& predict(const std::vector<double>& v);
    // The Huber cost of rows at v, in noise floors.
    double robust_cost(const std::vector<double>& v, const std::vector<std::size_t>& rows);
    // Fits on rows from `start` (a grid search first when asked); returns the values and the
    // covariance-based standard errors (inflated for autocorrelation by 1/sqrt(neff_factor)).
    std::pair<std::vector<double>, std::vector<double>> solve(std::vector<double> start,
                                                              const std::vector<std::size_t>& rows, bool grid,
                                                              double neff_factor);
    const ExplainData& data() const { return d_; }

private:
    static constexpr std::size_t kPredictionCache = 16;
    const ExplainData& d_;
    physics::PhysicsConfig base_;
    Effect e_;
    std::vector<std::pair<std::vector<double>, std::vector<Wrench6>>> cache_;
};

// Step of the numerical derivatives outside Ceres (the tare's spread, the split refits), as a
// fraction of a parameter's search range.
inline constexpr double kSensitivityStep = 1e-3;

// The tare's own noise in each of the effect's parameters at v (see fit.cpp), for tare_samples
// averaged samples.
std::vector<double> tare_spread(const ExplainData& d, Fit& fit, const Effect& e, const std::vector<double>& v,
                                std::size_t tare_samples);

// The model the candidates are scored against: its physics, its prediction of the recording and
// the autocorrelation of its residual.
struct Baseline {
    physics::PhysicsConfig physics;
    std::vector<Wrench6> pred;
    double factor = 1;  // effective-sample factor
    double n_eff = 0;   // effective samples over every axis
};
Baseline baseline_of(const ExplainData& d, const physics::PhysicsConfig& c, std::vector<Wrench6> pred);
Baseline baseline_of(const ExplainData& d, const physics::PhysicsConfig& c);

}  // namespace dw::analysis
