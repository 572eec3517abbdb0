#include "physics/recording_chain.hpp"

#include <cmath>

namespace dw::physics {

RecordingChain::RecordingChain(const Effects& effects) : effects_(effects) {
    for (const auto* t : effect_types())
        if (t->enabled(effects)) at_[static_cast<std::size_t>(t->stage())].push_back(t);
}

std::array<double, 3> RecordingChain::position_error_m() const {
    std::array<double, 3> out{0, 0, 0};
    for (const auto* t : at(Stage::positions)) {
        const auto e = t->position_error_m(effects_);
        for (std::size_t k = 0; k < 3; ++k) out[k] += e[k];
    }
    return out;
}

void RecordingChain::sensor(const std::vector<double>& t, RecordedWrench& series) const {
    for (const auto* e : at(Stage::sensor)) e->on_sensor(effects_, t, series);
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
    apply_registered_effects(effects_, stamps, w);
}

void first_order_lag(double tau_s, const std::vector<double>& t, RecordedWrench& series) {
    if (!(tau_s > 0) || series.empty()) return;
    // dy/dt = (x - y) / tau with x linear between samples.
    Wrench6 x0 = series.front();
    for (std::size_t i = 1; i < series.size(); ++i) {
        const double dt = t[i] - t[i - 1], a = std::exp(-dt / tau_s), b = dt > 0 ? tau_s / dt * (1 - a) : 1.0;
        const Wrench6 x1 = series[i];
        for (std::size_t k = 0; k < 6; ++k)
            series[i][k] = a * series[i - 1][k] + x1[k] - a * x0[k] - b * (x1[k] - x0[k]);
        x0 = x1;
    }
}

}  // namespace dw::physics
