#include "physics/bodies.hpp"

#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::physics {

namespace {

void require_usable(const VehicleParams& v, const std::string& body) {
    const bool ok = std::isfinite(v.mass_kg) && v.mass_kg > 0 && v.rotors >= 1 && std::isfinite(v.prop_radius_m) &&
                    v.prop_radius_m > 0 && std::isfinite(v.motor_distance_m) && v.motor_distance_m > 0;
    if (!ok)
        throw InputError(log::cat("meta.json: vehicles.", body, ": mass ", v.mass_kg, " kg, ", v.rotors,
                                  " rotors, propeller radius ", v.prop_radius_m, " m, motor distance ",
                                  v.motor_distance_m, " m: every one must be positive and finite for the physics"));
}

}  // namespace

VehicleParams vehicle_of(const flight::Meta& m, const std::string& body, const VehicleParams& fallback) {
    const auto it = m.vehicles.find(body);
    const VehicleParams v = it == m.vehicles.end() ? fallback : it->second;
    require_usable(v, body);
    return v;
}

PhysicsConfig for_flight(PhysicsConfig c, const flight::Meta& m) {
    c.sufferer.vehicle = vehicle_of(m, m.sufferer, c.sufferer.vehicle);
    for (const auto& n : m.neighbours) (void)vehicle_of(m, n, c.neighbour);
    return c;
}

double near_radius(const VehicleParams& neighbour) { return kNearSizes * neighbour.motor_distance_m; }

std::vector<VehicleParams> neighbours_of(const flight::Meta& m, const PhysicsConfig& c) {
    std::vector<VehicleParams> out;
    for (const auto& n : m.neighbours) out.push_back(vehicle_of(m, n, c.neighbour));
    return out;
}

std::vector<double> encounter_radii(const flight::Meta& m, const PhysicsConfig& c) {
    std::vector<double> out;
    for (const auto& v : neighbours_of(m, c)) out.push_back(kEncounterSizes * v.motor_distance_m);
    return out;
}

}  // namespace dw::physics
