#include "analysis/replay.hpp"

#include <cmath>

#include "analysis/discrepancy.hpp"
#include "analysis/explain.hpp"
#include "flight/blocks.hpp"
#include "physics/bodies.hpp"

namespace dw::analysis {

Replay replay(const flight::Flight& f, const physics::PhysicsConfig& c) {
    const Resimulation sim(f, c);
    const auto blocks = flight::find_blocks(f, ExplainOptions{}.folds, physics::encounter_radii(f.meta, c));
    const auto info = describe(sim, blocks, c);
    Replay r;
    r.physics = sim.recorded(c);
    r.discrepancy = c.discrepancy.empty() ? std::vector<Wrench6>(r.physics.size(), Wrench6{})
                                          : discrepancy_at(c.discrepancy.front(), sim, info, r.physics);
    for (const auto& s : info) r.on_blocks.push_back(s.leg >= 0);
    r.measured_axes = sim.measured_axes();
    return r;
}

std::vector<Wrench6> Replay::with_discrepancy() const {
    auto w = physics;
    add(w, discrepancy);
    return w;
}

flight::AxisValues rms_on_blocks(const flight::Flight& f, const Replay& r, const std::vector<Wrench6>& w) {
    flight::AxisValues sum{};
    std::size_t n = 0;
    for (std::size_t i = 0; i < w.size() && i < f.wrench.size(); ++i) {
        if (!r.on_blocks[i]) continue;
        ++n;
        for (std::size_t a = 0; a < 6; ++a)
            if (r.measured_axes[a]) sum[a] += std::pow(f.wrench[i].w[a] - w[i][a], 2);
    }
    for (auto& v : sum) v = n > 0 ? std::sqrt(v / static_cast<double>(n)) : 0.0;
    return sum;
}

void add(std::vector<Wrench6>& a, const std::vector<Wrench6>& b) {
    for (std::size_t i = 0; i < a.size() && i < b.size(); ++i)
        for (std::size_t k = 0; k < 6; ++k) a[i][k] += b[i][k];
}

void add_wrench(flight::Flight& f, const std::vector<Wrench6>& w) {
    for (std::size_t i = 0; i < w.size() && i < f.wrench.size(); ++i)
        for (std::size_t a = 0; a < 6; ++a) f.wrench[i].w[a] += w[i][a];
}

void set_wrench(flight::Flight& f, const std::vector<Wrench6>& w) {
    for (std::size_t i = 0; i < w.size() && i < f.wrench.size(); ++i) f.wrench[i].w = w[i];
}

}  // namespace dw::analysis
