#include "analysis/noise.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/stats.hpp"

namespace dw::analysis {

const char* describe(FloorBasis b) {
    switch (b) {
        case FloorBasis::far_samples: return "the residual's spread where no neighbour is within";
        case FloorBasis::differences: return "no neighbour is ever far: the spread of successive differences";
    }
    return "";
}

NoiseFloor floor_of(const Resimulation& r, const std::vector<SampleInfo>& info, const std::vector<Wrench6>& pred,
                    double tare_s) {
    AxisValues sum{}, sq{};
    double n = 0;
    for (std::size_t i = 0; i < info.size(); ++i) {
        if (info[i].near || r.stamps()[i] < r.stamps().front() + tare_s + kTareSettle_s) continue;
        for (std::size_t a = 0; a < 6; ++a) {
            const double x = r.measured()[i][a] - pred[i][a];
            sum[a] += x;
            sq[a] += x * x;
        }
        n += 1;
    }
    NoiseFloor out;
    auto& s = out.sigma;
    const bool far = n >= kMinFarSamples;
    out.basis = far ? FloorBasis::far_samples : FloorBasis::differences;
    for (std::size_t a = 0; a < 6; ++a) {
        if (far) {
            s[a] = std::sqrt(std::max(0.0, sq[a] / n - (sum[a] / n) * (sum[a] / n)));
        } else {  // nobody is ever far: the spread of successive differences
            std::vector<double> residual;
            for (std::size_t i = 0; i < info.size(); ++i) residual.push_back(r.measured()[i][a] - pred[i][a]);
            s[a] = floor_from_differences(residual);
        }
        s[a] = std::max(s[a], kMinNoiseFloor);
    }
    return out;
}

double floor_from_differences(std::span<const double> residual) {
    return std::max(sd_from_differences(residual), kMinNoiseFloor);
}

PushNoise::PushNoise(const ExplainData& d, const std::vector<Wrench6>& pred, const physics::PredictionNoise& n)
    : d_(d), pred_(pred), n_(n) {
    if (n_.timing_spread_s <= 0) return;
    std::vector<double> p(pred.size());
    for (std::size_t a = 0; a < 6; ++a) {
        if (!d.sim.measured_axes()[a]) continue;
        for (std::size_t i = 0; i < pred.size(); ++i) p[i] = pred[i][a];
        rate_[a] = physics::push_rates(d.sim.stamps(), p);
    }
}

// A jet whose speed fluctuates by the turbulence intensity I scatters its force by 2 I F (F ∝ U²):
// s p; and when a wake arrives varies by tau: tau dp/dt.
double PushNoise::variance(std::size_t i, std::size_t a) const {
    const double push = n_.push_share * pred_[i][a];
    const double timing = rate_[a].empty() ? 0.0 : n_.timing_spread_s * rate_[a][i];
    return push * push + timing * timing;
}

double turbulent_variance(const ExplainData& d, const PushNoise& push, std::size_t i, std::size_t a) {
    const double buffet = d.buffeting[i][a];
    return push.variance(i, a) + buffet * buffet;
}

// Each sample's residual is divided by sqrt(sigma² + the push's noise + b²): the noise floor, the
// noise model's terms that grow with the push and its rate, and the jets' lateral buffeting b.
AxisValues excess_of(const ExplainData& d, const PushNoise& push) {
    const auto& pred = push.pred();
    AxisValues e{};
    for (auto i : d.on_legs)
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            const double r = d.sim.measured()[i][a] - pred[i][a];
            e[a] += r * r / (d.sigma[a] * d.sigma[a] + turbulent_variance(d, push, i, a));
        }
    for (auto& v : e) v = d.on_legs.empty() ? 0 : std::sqrt(v / static_cast<double>(d.on_legs.size()));
    return e;
}

std::vector<BandTurbulence> turbulence_by_band(const ExplainData& d, const std::vector<Wrench6>& pred,
                                               std::size_t axis) {
    std::array<double, kBands.size()> r2{}, p2{};
    std::array<std::size_t, kBands.size()> n{};
    const double floor = d.sigma[axis];
    for (auto i : d.on_legs) {
        const double p = pred[i][axis];
        if (!d.info[i].near || std::abs(p) < kTurbulencePush * floor) continue;
        const auto b = static_cast<std::size_t>(band_index(d.info[i].h));
        const double r = d.sim.measured()[i][axis] - p;
        r2[b] += r * r, p2[b] += 4 * p * p, ++n[b];
    }
    std::vector<BandTurbulence> out;
    for (std::size_t b = 0; b < kBands.size(); ++b)
        if (n[b] >= kMinTurbulenceSamples) {
            const double excess = std::max(0.0, r2[b] / static_cast<double>(n[b]) - floor * floor);
            out.push_back({b, n[b], std::sqrt(excess / (p2[b] / static_cast<double>(n[b])))});
        }
    return out;
}

double largest(const AxisValues& v) { return *std::max_element(v.begin(), v.end()); }

double neff_factor(const ExplainData& d, const std::vector<Wrench6>& pred) {
    constexpr double kMaxRho = 0.98, kMinFraction = 0.01;
    double num = 0, den = 0;
    for (std::size_t k = 1; k < d.on_legs.size(); ++k) {
        const auto i = d.on_legs[k], j = d.on_legs[k - 1];
        if (i != j + 1) continue;
        for (std::size_t a = 0; a < 6; ++a) {
            const double ri = (d.sim.measured()[i][a] - pred[i][a]) / d.sigma[a];
            const double rj = (d.sim.measured()[j][a] - pred[j][a]) / d.sigma[a];
            num += ri * rj;
            den += ri * ri;
        }
    }
    const double rho = den > 0 ? std::clamp(num / den, 0.0, kMaxRho) : 0.0;
    return std::clamp(ar1_independent_fraction(rho), kMinFraction, 1.0);
}

}  // namespace dw::analysis
