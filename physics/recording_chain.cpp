#include "physics/recording_chain.hpp"

#include <algorithm>
#include <cmath>

namespace dw::physics {

RecordingChain::RecordingChain(const Effects& effects) : effects_(effects) {
    for (const auto* t : effect_types())
        if (t->enabled(effects)) at_[static_cast<std::size_t>(t->stage())].push_back(t);
}

Vec3 RecordingChain::position_error_m() const {
    Vec3 out = Vec3::Zero();
    for (const auto* t : at(Stage::positions)) {
        const auto e = t->position_error_m(effects_);
        out += Vec3(e[0], e[1], e[2]);
    }
    return out;
}

namespace {
void add_to(Wrench6& w, const Wrench6& x, double scale = 1.0) {
    for (std::size_t a = 0; a < w.size(); ++a) w[a] += scale * x[a];
}
}  // namespace

Wrench6 RecordingChain::sufferer_force(const SuffererState& s) const {
    Wrench6 out{};
    for (const auto* t : at(Stage::sufferer)) add_to(out, t->sufferer_force(effects_, s));
    return out;
}

SuffererState sufferer_state(const PhysicsConfig& c, const VehicleParams& v, const Vec3& p, const Vec3& velocity) {
    return {{p.x(), p.y(), p.z()},
            {velocity.x(), velocity.y(), velocity.z()},
            v.mass_kg * c.gravity_m_s2,
            v.prop_radius_m,
            c.air_density_kg_m3};
}

void RecordingChain::sensor(const std::vector<double>& t, RecordedWrench& series) const {
    for (const auto* e : at(Stage::sensor)) {
        if (series.empty()) return;
        Wrench6 x0 = series.front();  // the reading starts at the force
        for (std::size_t i = 1; i < series.size(); ++i) {
            const Wrench6 x1 = series[i];
            series[i] = series[i - 1];
            e->sensor_step(effects_, t[i] - t[i - 1], x0, x1, series[i]);
            x0 = x1;
        }
    }
}

Wrench6 RecordingChain::SensorStream::read(double t, const Wrench6& x) {
    const auto& effects = chain_.at(Stage::sensor);
    if (in_.empty()) {  // the first reading is the force
        in_.assign(effects.size(), x);
        out_.assign(effects.size(), x);
        t_ = t;
        return x;
    }
    if (!(t > t_)) return effects.empty() ? x : out_.back();
    Wrench6 input = x;
    for (std::size_t k = 0; k < effects.size(); ++k) {
        effects[k]->sensor_step(chain_.effects_, t - t_, in_[k], input, out_[k]);
        in_[k] = input;
        input = out_[k];
    }
    t_ = t;
    return input;
}

Samples RecordingChain::record(ChainInput in, Sampler& sampler) const {
    if (in.sufferer && acts_on_sufferer())
        for (std::size_t i = 0; i < in.force.size(); ++i) add_to(in.force[i], sufferer_force(in.sufferer(i)));
    if (in.felt) in.felt(in.force);
    sensor(in.t, in.force);
    Samples s = sampler.sample(in.t, in.force, clock_delay_s());
    sampler.tare(s, in.tare_s);
    for (std::size_t i = 0; i < s.w.size(); ++i) {
        calibration(s.w[i], in.recorded ? (*in.recorded)[i] : s.w[i]);
        if (!in.moments_measured) std::fill(s.w[i].begin() + 3, s.w[i].end(), 0.0);
    }
    recording(s.stamps, s.w);
    return s;
}

std::size_t tare_count(const std::vector<double>& t, double tare_s) {
    std::size_t n = 0;
    while (n < t.size() && t[n] < t.front() + tare_s) ++n;
    return n;
}

void Sampler::tare(Samples& s, double tare_s) const {
    const std::size_t n = tare_count(s.stamps, tare_s);
    if (n == 0) return;
    Wrench6 zero{};
    for (std::size_t i = 0; i < n; ++i) add_to(zero, s.w[i], 1.0 / static_cast<double>(n));
    for (auto& w : s.w) add_to(w, zero, -1.0);
}

Wrench6 RecordingChain::Live::read(double t, const Wrench6& x) {
    Wrench6 w = sensor_.read(t, x);
    chain_.calibration(w);
    return w;
}

void RecordingChain::calibration(Wrench6& w, const Wrench6& recorded) const {
    for (const auto* t : at(Stage::calibration)) t->on_calibration(effects_, w, recorded);
}

void RecordingChain::calibration(Wrench6& w) const {
    for (const auto* t : at(Stage::calibration)) t->on_calibration(effects_, w, w);
}

double RecordingChain::clock_delay_s() const {
    double delay = 0;
    for (const auto* t : at(Stage::clock)) delay += t->clock_delay_s(effects_);
    return delay;
}

void RecordingChain::recording(const std::vector<double>& stamps, RecordedWrench& w) const {
    for (const auto* t : at(Stage::recording)) t->on_recording(t->values(effects_), stamps, w);
}

void first_order_lag_step(double tau_s, double dt, const Wrench6& x0, const Wrench6& x1, Wrench6& y) {
    if (!(tau_s > 0)) {
        y = x1;
        return;
    }
    // dy/dt = (x - y) / tau with x linear over the step.
    const double a = std::exp(-dt / tau_s), b = dt > 0 ? tau_s / dt * (1 - a) : 1.0;
    for (std::size_t k = 0; k < 6; ++k) y[k] = a * y[k] + x1[k] - a * x0[k] - b * (x1[k] - x0[k]);
}

}  // namespace dw::physics
