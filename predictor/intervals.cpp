#include "predictor/intervals.hpp"

#include <cmath>

#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::predictor {

namespace {
double spread(const std::vector<double>& v) {  // the sample standard deviation
    double mean = 0, ss = 0;
    for (const double x : v) mean += x;
    mean /= static_cast<double>(v.size());
    for (const double x : v) ss += (x - mean) * (x - mean);
    return std::sqrt(ss / static_cast<double>(v.size() - 1));
}

bool nobody_near(const Sample& s) {
    for (const auto& x : s.neighbours())
        if (std::hypot(x[0], x[1]) <= kNobodyNearM) return false;
    return true;
}
}  // namespace

namespace {
// A sufferer's class: the four numbers a flight gives of it (a vehicle class of the physics matches
// on the same four).
std::string class_of(const Source& s) {
    const auto& v = s.sufferer;
    return log::cat(v.mass_kg, " kg, ", v.rotors, " rotors, ", v.prop_radius_m, " m, ", v.motor_distance_m, " m");
}
}  // namespace

NoiseModel noise_model(const Dataset& all, double intensity) {
    NoiseModel m;
    m.intensity = intensity;
    const std::size_t n = all.sources.size();
    std::vector<std::array<std::vector<double>, 6>> far(n), every(n);
    for (const auto& s : all.samples)
        for (std::size_t a = 0; a < 6; ++a) {
            every[static_cast<std::size_t>(s.source)][a].push_back(s.y[a]);
            if (nobody_near(s)) far[static_cast<std::size_t>(s.source)][a].push_back(s.y[a]);
        }
    // Flights with nobody near long enough: their own floor, and their class's (the median of them).
    std::map<std::string, std::array<std::vector<double>, 6>> by_class;
    for (std::size_t i = 0; i < n; ++i) {
        if (far[i][kFdAxis].size() < kMinFloorSamples) continue;
        flight::AxisValues f{};
        for (std::size_t a = 0; a < 6; ++a) {
            f[a] = all.sources[i].measured[a] ? spread(far[i][a]) : NAN;
            by_class[class_of(all.sources[i])][a].push_back(f[a]);
        }
        m.floor[all.sources[i].name] = f;
    }
    for (std::size_t i = 0; i < n; ++i) {
        const auto& name = all.sources[i].name;
        if (m.floor.contains(name)) continue;
        const auto cls = by_class.find(class_of(all.sources[i]));
        (cls != by_class.end() ? m.from_class : m.from_differences).push_back(name);
        flight::AxisValues f{};
        for (std::size_t a = 0; a < 6; ++a)
            f[a] = !all.sources[i].measured[a] ? NAN
                   : cls != by_class.end()     ? median(cls->second[a])
                                               : sd_from_differences(every[i][a]);
        m.floor[name] = f;
    }
    return m;
}

double half_width(const NoiseModel& m, const std::string& source, std::size_t axis, double p) {
    const auto it = m.floor.find(source);
    if (it == m.floor.end()) return NAN;
    const double floor = it->second[axis], turbulent = 2 * m.intensity * p;
    return kZ95 * std::sqrt(floor * floor + turbulent * turbulent);
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
