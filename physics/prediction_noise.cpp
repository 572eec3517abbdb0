#include "physics/prediction_noise.hpp"

#include <cmath>

namespace dw::physics {

namespace {
constexpr int kCoordinateRounds = 4;   // alternations between the two parameters
constexpr int kGoldenIterations = 40;  // per search: the bracket shrinks to 0.618^40 of the range
constexpr double kGolden = 0.6180339887498949;

// The Gaussian negative log-likelihood (up to constants) of the samples under n.
double cost(std::span<const NoiseSample> samples, const PredictionNoise& n) {
    double c = 0;
    for (const auto& s : samples) {
        const double sd = prediction_sd(s.floor, n, s.p, s.p_rate);
        if (!(sd > 0)) continue;  // a sample without a floor, push or rate says nothing of n
        c += 2 * std::log(sd) + s.residual * s.residual / (sd * sd);
    }
    return c;
}

// The value of `x` within [lo, hi] that minimises f (golden-section search; where f is flat, the
// lowest: a parameter the samples cannot show is 0).
template <class F>
double golden_min(double lo, double hi, F f) {
    double a = lo, b = hi, c = b - kGolden * (b - a), d = a + kGolden * (b - a), fc = f(c), fd = f(d);
    for (int i = 0; i < kGoldenIterations; ++i) {
        if (fc <= fd) b = d, d = c, fd = fc, c = b - kGolden * (b - a), fc = f(c);
        else a = c, c = d, fc = fd, d = a + kGolden * (b - a), fd = f(d);
    }
    return (a + b) / 2;
}
}  // namespace

PredictionNoise prediction_noise_of(const PhysicsConfig& p) {
    if (p.prediction_noise.push_share > 0) return p.prediction_noise;
    return {kPushSharePerIntensity * turbulence_of(p), 0};
}

double prediction_sd(double floor, const PredictionNoise& n, double p, double p_rate) {
    const double push = n.push_share * p, timing = n.timing_spread_s * p_rate;
    return std::sqrt(floor * floor + push * push + timing * timing);
}

std::vector<double> push_rates(std::span<const double> t, std::span<const double> p) {
    std::vector<double> out(p.size(), 0.0);
    std::size_t lo = 0, hi = 0;
    for (std::size_t i = 0; i < p.size(); ++i) {
        while (t[i] - t[lo] > kRateHalfSpan_s) ++lo;  // the earliest within the span before
        if (hi < i) hi = i;
        while (hi + 1 < p.size() && t[hi + 1] - t[i] <= kRateHalfSpan_s) ++hi;  // the latest within it after
        if (t[hi] > t[lo]) out[i] = (p[hi] - p[lo]) / (t[hi] - t[lo]);
    }
    return out;
}

double PushRate::update(double t, double p) {
    while (!recent_.empty() && t - recent_.front().first > 2 * kRateHalfSpan_s) recent_.erase(recent_.begin());
    const double rate = !recent_.empty() && t > recent_.front().first
                            ? (p - recent_.front().second) / (t - recent_.front().first)
                            : 0.0;
    recent_.emplace_back(t, p);
    return rate;
}

PredictionNoise fit_prediction_noise(std::span<const NoiseSample> samples) {
    PredictionNoise n{};
    for (int round = 0; round < kCoordinateRounds; ++round) {
        n.push_share = golden_min(kPushShareRange.lo, kPushShareRange.hi, [&](double s) {
            return cost(samples, {s, n.timing_spread_s});
        });
        n.timing_spread_s = golden_min(kTimingSpreadRange_s.lo, kTimingSpreadRange_s.hi, [&](double tau) {
            return cost(samples, {n.push_share, tau});
        });
    }
    return n;
}

}  // namespace dw::physics
