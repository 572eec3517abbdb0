#include "analysis/locate.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <optional>

#include "core/log.hpp"
#include "physics/effect_types.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

// Where a sample is, for locating residuals: over a stand, the arena cell of the neighbours'
// centre by altitude band and leg direction; for a flying sufferer, the nearest neighbour's
// position relative to it (horizontal offset x height above).
struct Cell {
    int band = 0, direction = 0, u = 0, v = 0;
    auto operator<=>(const Cell&) const = default;
};
constexpr double kArenaCell_m = 0.2;
constexpr double kRelativeCell_m = 0.1;

std::optional<Cell> cell_of(const SampleInfo& s, bool flying) {
    if (!s.near) return std::nullopt;
    if (flying)
        return Cell{0, 0, static_cast<int>(std::floor(s.offset / kRelativeCell_m)),
                    static_cast<int>(std::floor(s.above / kRelativeCell_m))};
    if (s.direction == 0) return std::nullopt;
    return Cell{band_index(s.h), s.direction, static_cast<int>(std::floor(s.n / kArenaCell_m)),
                static_cast<int>(std::floor(s.e / kArenaCell_m))};
}

std::string where(const Cell& c, bool flying, const std::string& formation) {
    if (flying)
        return log::cat("nearest neighbour ", c.u * kRelativeCell_m, "-", (c.u + 1) * kRelativeCell_m,
                        " m off horizontally, ", c.v * kRelativeCell_m, "-", (c.v + 1) * kRelativeCell_m,
                        " m above the sufferer, ", formation);
    const double cell = kArenaCell_m;
    return log::cat("relative altitude ", kBands[static_cast<std::size_t>(c.band)].name, ", N ", c.u * cell, "..",
                    (c.u + 1) * cell, " m, E ", c.v * cell, "..", (c.v + 1) * cell, " m, ", formation, ", ",
                    c.direction > 0 ? "+E" : "-E", " legs");
}

// One cell's mean residual on one axis, and its z (the standard error from the cell's own spread,
// at least the noise floor, with the sample count reduced for autocorrelation).
struct BinZ {
    int axis;
    Cell cell;
    double mean, z;
};
constexpr std::size_t kMinBinSamples = 10;

std::vector<BinZ> bins_of(const ExplainData& d, const std::vector<Wrench6>& pred, double factor) {
    struct Acc {
        double sum = 0, sq = 0;
        std::size_t n = 0;
    };
    std::map<std::pair<int, Cell>, Acc> bins;  // axis, cell
    const bool flying = d.sim.flying();
    for (auto i : d.on_legs) {
        const auto cell = cell_of(d.info[i], flying);
        if (!cell) continue;
        for (int a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[static_cast<std::size_t>(a)]) continue;
            const double r = d.sim.measured()[i][static_cast<std::size_t>(a)] - pred[i][static_cast<std::size_t>(a)];
            auto& b = bins[{a, *cell}];
            b.sum += r;
            b.sq += r * r;
            ++b.n;
        }
    }
    std::vector<BinZ> out;
    for (const auto& [key, b] : bins) {
        if (b.n < kMinBinSamples) continue;
        const auto& [a, c] = key;
        const double mean = b.sum / static_cast<double>(b.n);
        const double sd = std::max(std::sqrt(std::max(0.0, b.sq / static_cast<double>(b.n) - mean * mean)),
                                   d.sigma[static_cast<std::size_t>(a)]);
        out.push_back({a, c, mean, mean / (sd / std::sqrt(static_cast<double>(b.n) * factor))});
    }
    return out;
}

}  // namespace

std::vector<Region> locate(const ExplainData& d, const std::vector<Wrench6>& pred, double factor, double z_min,
                           const std::string& formation) {
    const bool flying = d.sim.flying();
    std::vector<Region> out;
    for (const auto& b : bins_of(d, pred, factor)) {
        if (std::abs(b.z) < z_min) continue;
        const int a = b.axis;
        const Cell& c = b.cell;
        Region r;
        r.axis = kAxes[a];
        r.mean_residual = b.mean;
        r.z = b.z;
        r.altitude_lo = flying ? c.v * kRelativeCell_m : kBands[static_cast<std::size_t>(c.band)].lo;
        r.altitude_hi = flying ? (c.v + 1) * kRelativeCell_m : kBands[static_cast<std::size_t>(c.band)].hi;
        r.direction = c.direction;
        r.where = where(c, flying, formation);
        out.push_back(r);
    }
    std::sort(out.begin(), out.end(), [](const Region& x, const Region& y) { return std::abs(x.z) > std::abs(y.z); });
    if (out.size() > kMaxRegions) out.resize(kMaxRegions);
    return out;
}

std::vector<Shift> shifts(const ExplainData& d, const physics::PhysicsConfig& base, const ExplainOptions& o) {
    // Per leg direction and altitude band: the clock shift that best aligns recording and model.
    std::map<std::pair<int, int>, std::vector<double>> sse;  // (direction, band) -> SSE per shift
    std::map<std::pair<int, int>, std::pair<std::size_t, double>> count;
    const double step = o.shift_step_s;
    const auto half = static_cast<long>(std::floor(o.shift_half_width_s / step + 1e-9));
    std::vector<double> grid;
    for (long k = -half; k <= half; ++k) grid.push_back(static_cast<double>(k) * step);
    // The shift moves the stamps' clock: the effect the lab's time service measures.
    const auto& clock = physics::clock_effect();
    const double base_offset = clock.in_force(base.effects).front();
    for (std::size_t g = 0; g < grid.size(); ++g) {
        physics::PhysicsConfig c = base;
        clock.set(c.effects, {base_offset + grid[g]});
        const auto p = d.predict(c);
        for (auto i : d.on_legs) {
            const auto& s = d.info[i];
            if (!s.near || (!d.sim.flying() && s.direction == 0)) continue;
            auto& v = sse[{s.direction, band_index(s.h)}];
            v.resize(grid.size());
            for (std::size_t a = 0; a < 6; ++a) v[g] += norm_sq(d, p, i, a);
            if (g == 0) {
                auto& cn = count[{s.direction, band_index(s.h)}];
                ++cn.first;
                cn.second += s.h;
            }
        }
    }
    std::vector<Shift> out;
    for (const auto& [key, v] : sse) {
        const auto k = static_cast<std::size_t>(std::min_element(v.begin(), v.end()) - v.begin());
        double best = grid[k];
        if (k > 0 && k + 1 < v.size()) {  // parabola through the minimum and its neighbours
            const double den = v[k - 1] - 2 * v[k] + v[k + 1];
            if (den > 0) best += 0.5 * step * (v[k - 1] - v[k + 1]) / den;
        }
        const auto& cn = count[key];
        out.push_back({key.first, kBands[static_cast<std::size_t>(key.second)].name,
                       cn.second / static_cast<double>(cn.first), best, cn.first});
    }
    return out;
}

}  // namespace dw::analysis
