#include "predictor/intervals.hpp"

#include <cmath>

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
    m.intensity = turbulence_intensity(physics);
    const std::size_t n = all.sources.size();
    std::vector<std::array<std::vector<double>, 6>> far(n), every(n);
    for (const auto& s : all.samples) {
        const auto i = static_cast<std::size_t>(s.source);
        const bool alone = nobody_near(s, all.sources[i]);
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

double interval_half_width(double floor, double intensity, double p) {
    const double turbulent = 2 * intensity * p;
    return kZ95 * std::sqrt(floor * floor + turbulent * turbulent);
}

double f_d_half_width(const physics::PhysicsConfig& physics, const physics::VehicleParams& sufferer, double p) {
    const auto* k = physics::class_of(physics, sufferer);
    if (!k || !(k->noise_floor_n > 0)) return 0;
    return interval_half_width(k->noise_floor_n, turbulence_intensity(physics), p);
}

double half_width(const NoiseModel& m, const std::string& source, std::size_t axis, double p) {
    const auto it = m.floor.find(source);
    return it == m.floor.end() ? NAN : interval_half_width(it->second[axis], m.intensity, p);
}

double coverage(const ForceModel& model, const Dataset& d, const NoiseModel& noise, std::size_t axis) {
    std::size_t inside = 0, counted = 0;
    for (const auto& s : d.samples) {
        const auto& source = d.sources[static_cast<std::size_t>(s.source)];
        const double p = model.predict(s, source)[axis], w = half_width(noise, source.name, axis, p);
        if (!std::isfinite(p) || !std::isfinite(w) || !std::isfinite(s.y[axis])) continue;
        ++counted;
        inside += std::abs(s.y[axis] - p) <= w;
    }
    return counted ? static_cast<double>(inside) / static_cast<double>(counted) : NAN;
}

}  // namespace dw::predictor
