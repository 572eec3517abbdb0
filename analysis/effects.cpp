#include "analysis/effects.hpp"

#include <algorithm>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::analysis {

namespace {
std::vector<double> range(double a, double b, int n) {
    std::vector<double> v;
    for (int i = 0; i < n; ++i) v.push_back(a + (b - a) * i / (n - 1));
    return v;
}
}  // namespace

std::vector<Effect> all_effects() {
    return {
        {"clock_offset", {{"offset_s", -0.5, 0.5, range(-0.3, 0.3, 25), 0.0}}},
        {"sensor_lag", {{"tau_s", 0.0, 0.5, range(0.0, 0.3, 13), 0.0}}},
        {"wake_transport", {{"delay_scale", 0.0, 5.0, range(0.0, 3.0, 7), 1.0}}},
        {"position_offset", {{"offset_n_m", -0.3, 0.3, {}, 0.0}, {"offset_e_m", -0.3, 0.3, {}, 0.0}, {"offset_d_m", -0.3, 0.3, {}, 0.0}}},
        {"force_scale", {{"scale", 0.3, 3.0, {}, 1.0}}},
        {"cell_crosstalk", {{"coefficient", -0.5, 0.5, {}, 0.0}}},
        {"jet_merging", {{"contraction", 0.05, 1.0, range(0.2, 1.0, 5), 0.8}}},
        {"floor_recirculation", {{"coefficient", 0.0, 0.3, range(0.0, 0.1, 5), 0.02}}},
        {"body_drag", {{"cda_h_m2", 0.0, 0.1, {}, 0.0}, {"cda_v_m2", 0.0, 0.1, {}, 0.0}}},
        {"ground_effect", {{"coefficient", 0.0, 50.0, range(0.0, 20.0, 5), 0.0}}},
    };
}

std::vector<Effect> effects_named(const std::vector<std::string>& names) {
    std::vector<Effect> out;
    const auto all = all_effects();
    for (const auto& n : names) {
        auto it = std::find_if(all.begin(), all.end(), [&](const Effect& e) { return e.name == n; });
        if (it == all.end()) {
            std::string known;
            for (const auto& e : all) known += (known.empty() ? "" : ", ") + e.name;
            throw InputError(log::cat("--effects: unknown effect '", n, "' (expected one of ", known, ")"));
        }
        out.push_back(*it);
    }
    return out;
}

bool Effect::changes_flow() const {
    return name == "wake_transport" || name == "position_offset" || name == "jet_merging" || name == "floor_recirculation";
}

std::vector<double> Effect::neutral() const {
    std::vector<double> v;
    for (const auto& p : params) v.push_back(p.start);
    return v;
}

void Effect::apply(physics::PhysicsConfig& c, const std::vector<double>& v) const {
    auto& fx = c.effects;
    if (name == "clock_offset") fx.clock_offset = {true, v[0]};
    else if (name == "sensor_lag") fx.sensor_lag = {true, v[0]};
    else if (name == "wake_transport") fx.wake_transport = {true, v[0]};
    else if (name == "position_offset") fx.position_offset = {true, {v[0], v[1], v[2]}};
    else if (name == "force_scale") fx.force_scale = {true, v[0]};
    else if (name == "cell_crosstalk") fx.cell_crosstalk = {true, from, to, v[0]};
    else if (name == "jet_merging") {
        fx.jet_merging.enabled = true;
        fx.jet_merging.contraction = v[0];
    } else if (name == "floor_recirculation") {
        fx.floor_recirculation.enabled = true;
        fx.floor_recirculation.coefficient = v[0];
    } else if (name == "body_drag") {
        fx.body_drag = {true, v[0], v[1]};
    } else if (name == "ground_effect") {
        fx.ground_effect = {true, v[0]};
    }
}

}  // namespace dw::analysis
