#include "predictor/intervals.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::predictor {

namespace {

// Every neighbour beyond its near radius (physics/bodies.hpp; one not described: the sufferer's size).
bool nobody_near(const Sample& s, const Source& source) {
    for (int j = 0; j < s.k; ++j) {
        const auto who = static_cast<std::size_t>(s.who[static_cast<std::size_t>(j)]);
        const auto& v = who < source.neighbours.size() ? source.neighbours[who] : source.sufferer;
        const auto& x = s.x[static_cast<std::size_t>(j)];
        if (std::hypot(x[0], x[1]) <= physics::near_radius(v)) return false;
    }
    return true;
}

// The physics predicts no push on s (physics::quiet_push; a geometry it cannot take is not quiet).
bool quiet(const PhysicsModel& model, const Sample& s, const Source& source) {
    try {
        return physics::quiet_push(model.predict(s, source)[kFdAxis]);
    } catch (const InputError&) {
        return false;
    }
}

// The samples of each source, in time order (indices into d.samples).
std::vector<std::vector<std::size_t>> by_source(const Dataset& d) {
    std::vector<std::vector<std::size_t>> out(d.sources.size());
    for (std::size_t i = 0; i < d.samples.size(); ++i) out[static_cast<std::size_t>(d.samples[i].source)].push_back(i);
    for (auto& idx : out)
        std::stable_sort(idx.begin(), idx.end(), [&](auto a, auto b) { return d.samples[a].t < d.samples[b].t; });
    return out;
}

// Each sample's predicted `axis` and its rate of change along its flight (physics::push_rates).
struct Predicted {
    std::vector<double> p, rate;
};
Predicted predicted(const ForceModel& model, const Dataset& d, std::size_t axis) {
    Predicted out{std::vector<double>(d.samples.size()), std::vector<double>(d.samples.size(), 0.0)};
    for (std::size_t i = 0; i < d.samples.size(); ++i) {
        const auto& s = d.samples[i];
        out.p[i] = model.predict(s, d.sources[static_cast<std::size_t>(s.source)])[axis];
    }
    for (const auto& idx : by_source(d)) {
        std::vector<double> t, p;
        for (auto i : idx) t.push_back(d.samples[i].t), p.push_back(std::isfinite(out.p[i]) ? out.p[i] : 0.0);
        const auto r = physics::push_rates(t, p);
        for (std::size_t k = 0; k < idx.size(); ++k) out.rate[idx[k]] = r[k];
    }
    return out;
}

// A sufferer's class: the four numbers a flight gives of it (a vehicle class of the physics matches
// on the same four).
std::string class_key(const Source& s) {
    const auto& v = s.sufferer;
    return log::cat(v.mass_kg, " kg, ", v.rotors, " rotors, ", v.prop_radius_m, " m, ", v.motor_distance_m, " m");
}

// The floor of a flight with too few samples with nobody near, per axis (the lists say which).
flight::AxisValues floor_elsewhere(const Source& source, const std::array<std::vector<double>, 6>& every,
                                   const std::array<std::vector<double>, 6>* dataset_class,
                                   const physics::VehicleClass* calibrated, NoiseModel& m) {
    const bool from_physics = calibrated && calibrated->noise_floor_n > 0;
    (from_physics || dataset_class ? m.from_class : m.from_differences).push_back(source.name);
    flight::AxisValues f{};
    for (std::size_t a = 0; a < 6; ++a)
        f[a] = !source.measured[a]            ? NAN
               : a == kFdAxis && from_physics ? calibrated->noise_floor_n
               : dataset_class                ? median((*dataset_class)[a])
                                              : sd_from_differences(every[a]);
    return f;
}
}  // namespace

NoiseModel noise_model(const Dataset& all, const physics::PhysicsConfig& physics) {
    NoiseModel m;
    m.noise = physics::prediction_noise_of(physics);
    const std::size_t n = all.sources.size();
    const PhysicsModel quiet_model(physics);
    std::vector<std::array<std::vector<double>, 6>> far(n), every(n);
    for (const auto& s : all.samples) {
        const auto i = static_cast<std::size_t>(s.source);
        const bool alone = nobody_near(s, all.sources[i]) || quiet(quiet_model, s, all.sources[i]);
        for (std::size_t a = 0; a < 6; ++a) {
            every[i][a].push_back(s.y[a]);
            if (alone) far[i][a].push_back(s.y[a]);
        }
    }
    // Flights with nobody near long enough: their own floor, and their class's (the median of them).
    std::map<std::string, std::array<std::vector<double>, 6>> by_class;
    for (std::size_t i = 0; i < n; ++i) {
        if (far[i][kFdAxis].size() < physics::kMinFarSamples) continue;
        flight::AxisValues f{};
        for (std::size_t a = 0; a < 6; ++a) {
            f[a] = all.sources[i].measured[a] ? standard_deviation(far[i][a]) : NAN;
            by_class[class_key(all.sources[i])][a].push_back(f[a]);
        }
        m.floor[all.sources[i].name] = f;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const Source& source = all.sources[i];
        if (m.floor.contains(source.name)) continue;
        const auto cls = by_class.find(class_key(source));
        m.floor[source.name] = floor_elsewhere(source, every[i], cls == by_class.end() ? nullptr : &cls->second,
                                               physics::class_of(physics, source.sufferer), m);
    }
    return m;
}

double interval_half_width(double floor, const physics::PredictionNoise& n, double p, double p_rate) {
    return kZ95 * physics::prediction_sd(floor, n, p, p_rate);
}

double f_d_half_width(const physics::PhysicsConfig& physics, const physics::VehicleParams& sufferer, double p,
                      double p_rate) {
    const auto* k = physics::class_of(physics, sufferer);
    if (!k || !(k->noise_floor_n > 0)) return 0;
    return interval_half_width(k->noise_floor_n, physics::prediction_noise_of(physics), p, p_rate);
}

double half_width(const NoiseModel& m, const std::string& source, std::size_t axis, double p, double p_rate) {
    const auto it = m.floor.find(source);
    return it == m.floor.end() ? NAN : interval_half_width(it->second[axis], m.noise, p, p_rate);
}

double coverage(const ForceModel& model, const Dataset& d, const NoiseModel& noise, std::size_t axis) {
    std::size_t inside = 0, counted = 0;
    const auto pred = predicted(model, d, axis);
    for (std::size_t i = 0; i < d.samples.size(); ++i) {
        const auto& s = d.samples[i];
        const auto& source = d.sources[static_cast<std::size_t>(s.source)];
        const double p = pred.p[i], w = half_width(noise, source.name, axis, p, pred.rate[i]);
        if (!std::isfinite(p) || !std::isfinite(w) || !std::isfinite(s.y[axis])) continue;
        ++counted;
        inside += std::abs(s.y[axis] - p) <= w;
    }
    return counted ? static_cast<double>(inside) / static_cast<double>(counted) : NAN;
}

}  // namespace dw::predictor
