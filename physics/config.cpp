#include "physics/config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/keys.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "physics/effect_types.hpp"
#include "core/numbers.hpp"
#include "flight/flight.hpp"
#include "physics/effect_types.hpp"

namespace dw::physics {

int axis_index(const std::string& name) {
    const auto i = find_name(flight::kAxes, name);
    return i ? static_cast<int>(*i) : -1;
}

// Every key of the physics configuration, declared once: parse_physics reads and to_yaml writes
// through these (core/keys.hpp).
namespace {

constexpr const char* kFormat = "downwash-physics/1";

void vehicle_keys(KeyVisitor& k, VehicleParams& v) {
    k.number("mass_kg", v.mass_kg, flight::kVehicleMassRange);
    k.integer("rotors", v.rotors, flight::kRotorsRange);
    k.number("prop_radius_m", v.prop_radius_m, flight::kPropRadiusRange);
    k.number("motor_distance_m", v.motor_distance_m, flight::kMotorDistanceRange);
}

void coefficient_keys(KeyVisitor& k, JetCoefficients& j) {
    k.number("strength", j.strength, {0.1, 1000});
    k.number("origin", j.origin, {0, 100});
    k.number("width", j.width, {0.001, 10});
}

// The effects that regroup jets (jets merging), for the aggregation's message.
std::string regrouping_effects() {
    std::vector<std::string> names;
    for (const auto* t : effect_types())
        if (t->regroups_jets()) names.push_back(t->name());
    return log::join(names);
}

void jet_keys(KeyVisitor& k, PhysicsConfig& c) {
    k.section("jet", [&](KeyVisitor& jet) {
        jet.enumeration("model", c.jet_model, kJetModelNames, "jet model");
        jet.flag("radial_inflow", c.radial_inflow);
        jet.section("bauersfeld", [&](KeyVisitor& b) { coefficient_keys(b, c.bauersfeld); });
        jet.section("jain", [&](KeyVisitor& j) {
            j.number("c_ax", c.jain.c_ax, {0.01, 100});
            j.number("c_rad", c.jain.c_rad, {0.01, 1000});
            j.number("z0_m", c.jain.z0_m, {-5, 5});
            j.number("diameter_m", c.jain.diameter_m, {0.01, 5});
        });
    });
    k.enumeration("aggregation", c.aggregation, kAggregationNames, "aggregation",
                  "; momentum merging is an effect: " + regrouping_effects());
}

void body_keys(KeyVisitor& k, PhysicsConfig& c) {
    k.section("sufferer", [&](KeyVisitor& s) {
        SuffererParams& x = c.sufferer;
        s.section("vehicle", [&](KeyVisitor& v) { vehicle_keys(v, x.vehicle); });
        s.number("drag_coefficient", x.drag_coefficient, {0, 5});
        s.number("lateral_drag_coefficient", x.lateral_drag_coefficient, {0, 5});
        s.number("arm_width_m", x.arm_width_m, {0, 1});
        s.number("body_size_m", x.body_size_m, {0, 1});
        s.integer("disc_rings", x.disc_rings, {1, 20});
        s.integer("disc_sectors", x.disc_sectors, {1, 64});
        s.flag("thrust_loss", x.thrust_loss);
        s.number("kv_omega_n_per_mps", x.kv_omega_n_per_mps, {0, 10});
        s.number("rotor_drag_n_per_mps", x.rotor_drag_n_per_mps, {0, 10});
    });
    k.section("neighbour", [&](KeyVisitor& v) { vehicle_keys(v, c.neighbour); });
}

void class_keys(KeyVisitor& k, PhysicsConfig& c) {
    std::size_t count = c.classes.size();
    k.list("classes", count, [&](KeyVisitor& item, std::size_t i) {
        if (c.classes.size() <= i) c.classes.resize(i + 1);
        VehicleClass& x = c.classes[i];
        item.text("name", x.name);
        item.section("vehicle", [&](KeyVisitor& v) { vehicle_keys(v, x.vehicle); });
        item.section("jet", [&](KeyVisitor& j) { coefficient_keys(j, x.jet); });
        item.number("drag_coefficient", x.drag_coefficient, {0, 5});
        item.number("kv_omega_n_per_mps", x.kv_omega_n_per_mps, {0, 10});
        item.number("noise_floor_n", x.noise_floor_n, kNoiseFloorRange);
    });
    c.classes.resize(count);
    k.text("calibration", c.calibration);
}

void stand_keys(KeyVisitor& k, StandParams& x) {
    k.number("height_m", x.height_m, {0.1, 10});
    k.number("lateral_radius_m", x.lateral_radius_m, {0.01, 1});
    k.number("counts_per_newton", x.counts_per_newton, {1, 1e7});
    k.number("offset_sigma_counts", x.offset_sigma_counts, {0, 4e6});
    k.number("rate_hz", x.rate_hz, {1, 1000});
    k.number("rate_skew", x.rate_skew, {0, 0.2});
    k.number("noise_n", x.noise_n, kCellNoiseRange);
    k.number("tare_s", x.tare_s, {0.05, 60});
}

void noise_keys(KeyVisitor& k, PhysicsConfig& c) {
    k.section("turbulence", [&](KeyVisitor& s) {
        TurbulenceParams& x = c.turbulence;
        s.flag("enabled", x.enabled);
        s.number("intensity", x.intensity, kTurbulenceIntensityRange);
        s.number("time_scale_s", x.time_scale_s, {1e-4, 10});
        s.number("lateral_intensity", x.lateral_intensity, {0, 1});
        s.number("lateral_time_scale_s", x.lateral_time_scale_s, {1e-4, 10});
    });
    k.section("prediction_noise", [&](KeyVisitor& s) {
        s.number("push_share", c.prediction_noise.push_share, kPushShareRange);
        s.number("timing_spread_s", c.prediction_noise.timing_spread_s, kTimingSpreadRange_s);
    });
    k.section("dynamics", [&](KeyVisitor& s) {
        DynamicsParams& x = c.dynamics;
        s.number("natural_frequency_rad_s", x.natural_frequency_rad_s, {0.1, 50});
        s.number("damping", x.damping, {0.05, 5});
        s.number("hover_noise_m", x.hover_noise_m, {0, 1});
        s.number("hover_noise_time_s", x.hover_noise_time_s, {0.01, 100});
        s.number("rate_hz", x.rate_hz, {200, 10000});
    });
    k.section("mocap", [&](KeyVisitor& s) {
        s.number("rate_hz", c.mocap.rate_hz, {1, 1000});
        s.number("noise_m", c.mocap.noise_m, {0, 0.1});
        s.require(c.mocap.rate_hz <= c.dynamics.rate_hz, "rate_hz", "must not exceed dynamics.rate_hz");
    });
}

// effects: the switchable physics of ../shared/FLIGHT_FORMAT.md, each declared by its own type.
void effect_keys(KeyVisitor& k, Effects& e) {
    const auto each = [&](KeyVisitor& s) {
        for (const auto* t : effect_types()) s.section(t->name(), [&](KeyVisitor& one) { t->keys(one, e); });
    };
    k.section("effects", each, "no such effect");
}

// discrepancy: the learnt discrepancy, when dw-explain carried one (a list of none or one).
void discrepancy_keys(KeyVisitor& k, PhysicsConfig& c) {
    constexpr Range kAny{-1e12, 1e12};
    std::size_t count = c.discrepancy.size();
    k.list("discrepancy", count, [&](KeyVisitor& item, std::size_t i) {
        if (c.discrepancy.size() <= i) c.discrepancy.resize(i + 1);
        LearntDiscrepancy& x = c.discrepancy[i];
        item.text("flight", x.flight);
        item.number("heldout_gain", x.heldout_gain, {-1e3, 1});
        item.number("height_lo_m", x.height_lo_m, {-100, 100});
        item.number("height_step_m", x.height_step_m, {0, 100});
        item.number("height_width_m", x.height_width_m, {1e-6, 100});
        item.number("t0_s", x.t0_s, {-1e9, 1e9});
        item.number("t1_s", x.t1_s, {-1e9, 1e9});
        item.integer("drift_bumps", x.drift_bumps, {0, 100000});
        item.number("push_top", x.push_top, {1e-12, 1e12});
        item.numbers("sigma", x.sigma, {1e-12, 1e6}, "expected six noise floors, one per axis");
        item.matrix("coefficients", x.coefficients, x.rows, x.inputs, kAny);
        item.require(x.rows == 6, "coefficients", "expected six rows, one per axis");
        item.require(x.t1_s >= x.t0_s, "t1_s", "must not be before t0_s");
    });
    if (count > 1) k.require(false, "discrepancy", "expected at most one");
    c.discrepancy.resize(count);
}

void physics_keys(KeyVisitor& k, PhysicsConfig& c) {
    k.constant("format", kFormat);
    k.number("air_density_kg_m3", c.air_density_kg_m3, {0.5, 2.0});
    k.number("gravity_m_s2", c.gravity_m_s2, {1.0, 20.0});
    jet_keys(k, c);
    body_keys(k, c);
    k.section("stand", [&](KeyVisitor& s) { stand_keys(s, c.stand); });
    noise_keys(k, c);
    effect_keys(k, c.effects);
    class_keys(k, c);
    discrepancy_keys(k, c);
}

}  // namespace

namespace {
constexpr double kSameClass = 1e-6;  // relative: meta.json and a physics file carry the same numbers
bool close(double a, double b) { return std::abs(a - b) <= kSameClass * std::max(std::abs(a), std::abs(b)); }
}  // namespace

const VehicleClass* class_of(const PhysicsConfig& c, const VehicleParams& v) {
    for (const auto& k : c.classes) {
        const auto& w = k.vehicle;
        if (w.rotors == v.rotors && close(w.mass_kg, v.mass_kg) && close(w.prop_radius_m, v.prop_radius_m) &&
            close(w.motor_distance_m, v.motor_distance_m))
            return &k;
    }
    return nullptr;
}

JetCoefficients jet_coefficients(const PhysicsConfig& c, const VehicleParams& v) {
    const auto* k = class_of(c, v);
    return k ? k->jet : c.bauersfeld;
}

SuffererParams sufferer_as(const PhysicsConfig& c, const VehicleParams& v) {
    SuffererParams s = c.sufferer;
    s.vehicle = v;
    if (const auto* k = class_of(c, v)) {
        s.drag_coefficient = k->drag_coefficient;
        s.kv_omega_n_per_mps = k->kv_omega_n_per_mps;
    }
    return s;
}

PhysicsConfig parse_physics(const std::string& yaml, const std::string& file) {
    PhysicsConfig c;
    read_keys(load_yaml(yaml, file), file, [&](KeyVisitor& k) { physics_keys(k, c); });
    return c;
}

PhysicsConfig load_physics(const std::string& path) {
    return parse_physics(read_file(path, "physics configuration"), path);
}

PhysicsConfig physics_or_defaults(const std::string& path) {
    return path.empty() ? PhysicsConfig{} : load_physics(path);
}

KeyValues key_values(const PhysicsConfig& c) {
    PhysicsConfig copy = c;  // the visitor takes what it reads by reference; collecting leaves it as it is
    return key_values(copy);
}

KeyValues key_values(PhysicsConfig& c) {
    return dw::key_values([&](KeyVisitor& k) { physics_keys(k, c); });
}

std::string to_yaml(const PhysicsConfig& c) {
    PhysicsConfig copy = c;  // the visitor takes what it reads by reference; writing leaves it as it is
    YAML::Emitter o;
    o.SetDoublePrecision(10);
    write_keys(o, [&](KeyVisitor& k) { physics_keys(k, copy); });
    return std::string(o.c_str()) + "\n";
}

}  // namespace dw::physics
