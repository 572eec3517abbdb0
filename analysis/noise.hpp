#pragma once
// What noise alone leaves in a recording, for the explainer: the noise floor per axis, the
// residual's size against noise and turbulence, and how many samples count as independent.
#include <array>
#include <span>
#include <vector>

#include "analysis/fit.hpp"
#include "physics/bodies.hpp"
#include "physics/prediction_noise.hpp"

namespace dw::analysis {

// The noise floor per axis: the residual's spread where nobody is near (after the tare and
// kTareSettle_s), or, when nobody ever is, from successive differences. At least kMinNoiseFloor.
// Which of those it is, for the report.
enum class FloorBasis { far_samples, differences };
const char* describe(FloorBasis b);
struct NoiseFloor {
    AxisValues sigma{};
    FloorBasis basis = FloorBasis::far_samples;
};
NoiseFloor floor_of(const Resimulation& r, const std::vector<SampleInfo>& info, const std::vector<Wrench6>& pred,
                    double tare_s);
inline constexpr double kTareSettle_s = 0.5;
inline constexpr double kMinNoiseFloor = 1e-4;  // N or N·m
using physics::kMinFarSamples;                  // fewer far samples: the differences' spread
// The floor from one axis's residual when nobody is ever far: its successive differences' spread.
double floor_from_differences(std::span<const double> residual);

// The noise model (physics/prediction_noise.hpp: the physics' calibrated one, else 2 I and no
// timing term) on one flight's predictions pred: what it adds beyond the floor at each sample,
// (s p)² + (tau dp/dt)², with dp/dt along the recording. pred is held by reference.
class PushNoise {
public:
    PushNoise(const ExplainData& d, const std::vector<Wrench6>& pred, const physics::PredictionNoise& n);
    double variance(std::size_t i, std::size_t a) const;  // N² (N·m² on a moment)
    double relative(std::size_t i, std::size_t a) const { return variance(i, a) / (d_.sigma[a] * d_.sigma[a]); }
    const std::vector<Wrench6>& pred() const { return pred_; }

private:
    const ExplainData& d_;
    const std::vector<Wrench6>& pred_;
    physics::PredictionNoise n_;
    std::array<std::vector<double>, 6> rate_;  // per measured axis; none without a timing term
};

// The variance beyond the floor at sample i on axis a: the push's (PushNoise) and the lateral
// buffeting's — the noise model's terms beside the floor's.
double turbulent_variance(const ExplainData& d, const PushNoise& push, std::size_t i, std::size_t a);

// The residual's RMS over the blocks against what noise and turbulence alone explain, per measured
// axis (0 where not measured); about 1 when the physics is right (see noise.cpp).
AxisValues excess_of(const ExplainData& d, const PushNoise& push);

double largest(const AxisValues& v);

// The jets' turbulence the residual shows, per vertical-separation band (kBands: the lowest
// neighbour's height above the sufferer): over the near samples where the push predicted on `axis`
// is at least kTurbulencePush noise floors, the intensity I with mean(r²) = floor² + (2 I p)² (0
// where the spread does not exceed the floor). What the mean flow leaves scatters like turbulence
// only if the mean flow is right there: the report says so.
struct BandTurbulence {
    std::size_t band = 0, samples = 0;
    double intensity = 0;
};
inline constexpr double kTurbulencePush = 3;              // noise floors
inline constexpr std::size_t kMinTurbulenceSamples = 50;  // fewer in a band: not measured there
// A band whose intensity exceeds the physics' this many times shows turbulence the physics left out.
inline constexpr double kTurbulenceBeyond = 1.5;
std::vector<BandTurbulence> turbulence_by_band(const ExplainData& d, const std::vector<Wrench6>& pred,
                                               std::size_t axis);

// The fraction of the samples on legs that count as independent, from the lag-1 autocorrelation
// of the normalised residual along legs.
double neff_factor(const ExplainData& d, const std::vector<Wrench6>& pred);

}  // namespace dw::analysis
