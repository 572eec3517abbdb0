#include "analysis/spectrum.hpp"

#include <algorithm>
#include <cmath>
#include <complex>

#include "core/stats.hpp"

namespace dw::analysis {

namespace {

// Per axis, the power at each frequency f0 + k df of the residuals r (one row per sample) at stamps t.
std::vector<std::array<double, 6>> periodogram(const std::vector<double>& t, const std::vector<Wrench6>& r, double f0,
                                               double df, std::size_t count) {
    const std::size_t n = t.size();
    std::vector<std::complex<double>> z(n), step(n);
    for (std::size_t i = 0; i < n; ++i) {
        z[i] = std::polar(1.0, -2 * M_PI * f0 * (t[i] - t[0]));
        step[i] = std::polar(1.0, -2 * M_PI * df * (t[i] - t[0]));
    }
    std::vector<std::array<double, 6>> out(count);
    for (std::size_t k = 0; k < count; ++k) {
        std::array<std::complex<double>, 6> s{};
        for (std::size_t i = 0; i < n; ++i) {
            for (std::size_t a = 0; a < 6; ++a) s[a] += r[i][a] * z[i];
            z[i] *= step[i];
        }
        for (std::size_t a = 0; a < 6; ++a) out[k][a] = std::norm(s[a]) / static_cast<double>(n);
    }
    return out;
}

}  // namespace

SpectralLine strongest_line(const ExplainData& d, const PushNoise& push) {
    const auto& pred = push.pred();
    SpectralLine best;
    if (d.on_legs.size() < 2) return best;
    std::vector<double> t;
    std::vector<Wrench6> r;
    for (auto i : d.on_legs) {
        t.push_back(d.sim.stamps()[i]);
        Wrench6 x{};
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            x[a] = (d.sim.measured()[i][a] - pred[i][a]) / d.sigma[a] / std::sqrt(1 + push.relative(i, a));
        }
        r.push_back(x);
    }
    const double span = t.back() - t.front();
    if (!(span > 0)) return best;
    const double df = 1 / span;
    const auto count = static_cast<std::size_t>((kMaxLineHz - kMinLineHz) / df);
    const auto window = static_cast<std::size_t>(kLocalHz / df);
    if (count < 2 * window + 1) return best;
    const auto p = periodogram(t, r, kMinLineHz, df, count);
    std::size_t axes = 0;
    for (std::size_t a = 0; a < 6; ++a) {
        if (!d.sim.measured_axes()[a]) continue;
        ++axes;
        for (std::size_t k = 0; k < count; ++k) {
            const std::size_t lo = k > window ? k - window : 0, hi = std::min(count, k + window + 1);
            std::vector<double> local;
            for (std::size_t j = lo; j < hi; ++j) local.push_back(p[j][a]);
            const double level = median(local) / std::log(2.0);
            const double ratio = level > 0 ? p[k][a] / level : 0;
            if (ratio > best.ratio)
                best = {static_cast<int>(a), kMinLineHz + static_cast<double>(k) * df, ratio, 1, 0, false};
        }
    }
    best.lines = count * axes;
    best.false_alarm = -std::expm1(static_cast<double>(best.lines) * std::log1p(-std::exp(-best.ratio)));
    best.significant = best.false_alarm < kLineAlpha;
    return best;
}

}  // namespace dw::analysis
