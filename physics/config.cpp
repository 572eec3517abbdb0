#include "physics/config.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "flight/flight.hpp"
#include "physics/effect_types.hpp"
#include "physics/yaml_section.hpp"

namespace dw::physics {
namespace {

void read_vehicle(Section s, VehicleParams& v) {
    s.number("mass_kg", v.mass_kg, 0.01, 100);
    s.integer("rotors", v.rotors, 1, 16);
    s.number("prop_radius_m", v.prop_radius_m, 0.005, 1.0);
    s.number("motor_distance_m", v.motor_distance_m, 0.02, 5.0);
}

}  // namespace

int axis_index(const std::string& name) {
    for (std::size_t i = 0; i < flight::kAxes.size(); ++i) {
        if (name == flight::kAxes[i]) return static_cast<int>(i);
    }
    return -1;
}
const char* axis_name(int i) { return flight::kAxes.at(static_cast<std::size_t>(i)); }

namespace {

// jet: model, radial inflow, Jain's constants; aggregation
void read_jet_and_aggregation(Section& top, PhysicsConfig& c) {
    {
        Section jet = top.sub("jet");
        const std::string model = jet.text("model", "bauersfeld");
        if (model == "bauersfeld") c.jet_model = JetModelKind::bauersfeld;
        else if (model == "jain") c.jet_model = JetModelKind::jain;
        else jet.fail(jet.get("model"), log::cat("unknown jet model '", model, "' (expected bauersfeld or jain)"), "model");
        jet.flag("radial_inflow", c.radial_inflow);
        Section jain = jet.sub("jain");
        jain.number("c_ax", c.jain.c_ax, 0.01, 100);
        jain.number("c_rad", c.jain.c_rad, 0.01, 1000);
        jain.number("z0_m", c.jain.z0_m, -5, 5);
        jain.number("diameter_m", c.jain.diameter_m, 0.01, 5);
    }
    {
        const std::string agg = top.text("aggregation", "force_sum");
        if (agg == "force_sum") c.aggregation = Aggregation::force_sum;
        else if (agg == "velocity_superposition") c.aggregation = Aggregation::velocity_superposition;
        else top.fail(top.get("aggregation"), log::cat("unknown aggregation '", agg,
                      "' (expected force_sum or velocity_superposition; momentum merging is the jet_merging effect)"), "aggregation");
    }
}

// sufferer, neighbour
void read_bodies(Section& top, PhysicsConfig& c) {
    {
        Section s = top.sub("sufferer");
        read_vehicle(s.sub("vehicle"), c.sufferer.vehicle);
        s.number("drag_coefficient", c.sufferer.drag_coefficient, 0, 5);
        s.number("lateral_drag_coefficient", c.sufferer.lateral_drag_coefficient, 0, 5);
        s.number("arm_width_m", c.sufferer.arm_width_m, 0, 1);
        s.number("body_size_m", c.sufferer.body_size_m, 0, 1);
        s.integer("disc_rings", c.sufferer.disc_rings, 1, 20);
        s.integer("disc_sectors", c.sufferer.disc_sectors, 1, 64);
        s.flag("thrust_loss", c.sufferer.thrust_loss);
        s.number("kv_omega_n_per_mps", c.sufferer.kv_omega_n_per_mps, 0, 10);
        s.number("rotor_drag_n_per_mps", c.sufferer.rotor_drag_n_per_mps, 0, 10);
    }
    read_vehicle(top.sub("neighbour"), c.neighbour);
}

// stand, turbulence, dynamics, mocap
void read_stand_and_noise(Section& top, PhysicsConfig& c) {
    {
        Section s = top.sub("stand");
        s.number("height_m", c.stand.height_m, 0.1, 10);
        s.number("lateral_radius_m", c.stand.lateral_radius_m, 0.01, 1);
        s.number("counts_per_newton", c.stand.counts_per_newton, 1, 1e7);
        s.number("offset_sigma_counts", c.stand.offset_sigma_counts, 0, 4e6);
        s.number("rate_hz", c.stand.rate_hz, 1, 1000);
        s.number("rate_skew", c.stand.rate_skew, 0, 0.2);
        s.number("noise_n", c.stand.noise_n, kCellNoiseRange.lo, kCellNoiseRange.hi);
        s.number("tare_s", c.stand.tare_s, 0.05, 60);
    }
    {
        Section s = top.sub("turbulence");
        s.flag("enabled", c.turbulence.enabled);
        s.number("intensity", c.turbulence.intensity, 0, 1);
        s.number("time_scale_s", c.turbulence.time_scale_s, 1e-4, 10);
        s.number("lateral_intensity", c.turbulence.lateral_intensity, 0, 1);
        s.number("lateral_time_scale_s", c.turbulence.lateral_time_scale_s, 1e-4, 10);
    }
    {
        Section s = top.sub("dynamics");
        s.number("natural_frequency_rad_s", c.dynamics.natural_frequency_rad_s, 0.1, 50);
        s.number("damping", c.dynamics.damping, 0.05, 5);
        s.number("hover_noise_m", c.dynamics.hover_noise_m, 0, 1);
        s.number("hover_noise_time_s", c.dynamics.hover_noise_time_s, 0.01, 100);
        s.number("rate_hz", c.dynamics.rate_hz, 200, 10000);
    }
    {
        Section s = top.sub("mocap");
        s.number("rate_hz", c.mocap.rate_hz, 1, 1000);
        s.number("noise_m", c.mocap.noise_m, 0, 0.1);
        if (c.mocap.rate_hz > c.dynamics.rate_hz) s.fail(s.get("rate_hz"), "must not exceed dynamics.rate_hz", "rate_hz");
    }
}

// effects: the switchable physics of ../shared/FLIGHT_FORMAT.md, each read by its own type.
void read_effects(Section& top, PhysicsConfig& c) {
    Section e = top.sub("effects");
    if (e.node() && e.node().IsMap())
        for (const auto& kv : e.node()) {
            const std::string name = kv.first.Scalar();
            bool known = false;
            for (const auto* t : effect_types()) known = known || t->name() == name;
            if (!known) e.fail(kv.first, log::cat("unknown key '", name, "': no such effect (expected one of ", effect_names(), ")"), name);
        }
    for (const auto* t : effect_types()) {
        Section s = e.sub(t->name());
        t->read(s, c.effects);
    }
}

}  // namespace

PhysicsConfig parse_physics(const std::string& yaml, const std::string& file) {
    const YAML::Node root = load_yaml(yaml, file);
    PhysicsConfig c;
    Section top(root, "", file);
    const std::string format = top.text("format", "downwash-physics/1");
    if (format != "downwash-physics/1") top.fail(top.get("format"), "expected downwash-physics/1", "format");
    top.number("air_density_kg_m3", c.air_density_kg_m3, 0.5, 2.0);
    top.number("gravity_m_s2", c.gravity_m_s2, 1.0, 20.0);
    read_jet_and_aggregation(top, c);
    read_bodies(top, c);
    read_stand_and_noise(top, c);
    read_effects(top, c);
    return c;
}

PhysicsConfig load_physics(const std::string& path) {
    return parse_physics(read_file(path, "physics configuration"), path);
}

std::string to_yaml(const PhysicsConfig& c) {
    YAML::Emitter o;
    o.SetDoublePrecision(10);
    auto vehicle = [&](const VehicleParams& v) {
        o << YAML::BeginMap << YAML::Key << "mass_kg" << YAML::Value << v.mass_kg << YAML::Key << "rotors"
          << YAML::Value << v.rotors << YAML::Key << "prop_radius_m" << YAML::Value << v.prop_radius_m
          << YAML::Key << "motor_distance_m" << YAML::Value << v.motor_distance_m << YAML::EndMap;
    };
    o << YAML::BeginMap;
    o << YAML::Key << "format" << YAML::Value << "downwash-physics/1";
    o << YAML::Key << "air_density_kg_m3" << YAML::Value << c.air_density_kg_m3;
    o << YAML::Key << "gravity_m_s2" << YAML::Value << c.gravity_m_s2;
    o << YAML::Key << "jet" << YAML::Value << YAML::BeginMap
      << YAML::Key << "model" << YAML::Value << (c.jet_model == JetModelKind::bauersfeld ? "bauersfeld" : "jain")
      << YAML::Key << "radial_inflow" << YAML::Value << c.radial_inflow
      << YAML::Key << "jain" << YAML::Value << YAML::BeginMap << YAML::Key << "c_ax" << YAML::Value << c.jain.c_ax
      << YAML::Key << "c_rad" << YAML::Value << c.jain.c_rad << YAML::Key << "z0_m" << YAML::Value << c.jain.z0_m
      << YAML::Key << "diameter_m" << YAML::Value << c.jain.diameter_m << YAML::EndMap << YAML::EndMap;
    o << YAML::Key << "aggregation" << YAML::Value
      << (c.aggregation == Aggregation::force_sum ? "force_sum" : "velocity_superposition");
    o << YAML::Key << "sufferer" << YAML::Value << YAML::BeginMap << YAML::Key << "vehicle" << YAML::Value;
    vehicle(c.sufferer.vehicle);
    o << YAML::Key << "drag_coefficient" << YAML::Value << c.sufferer.drag_coefficient
      << YAML::Key << "lateral_drag_coefficient" << YAML::Value << c.sufferer.lateral_drag_coefficient
      << YAML::Key << "arm_width_m" << YAML::Value << c.sufferer.arm_width_m
      << YAML::Key << "body_size_m" << YAML::Value << c.sufferer.body_size_m
      << YAML::Key << "disc_rings" << YAML::Value << c.sufferer.disc_rings
      << YAML::Key << "disc_sectors" << YAML::Value << c.sufferer.disc_sectors
      << YAML::Key << "thrust_loss" << YAML::Value << c.sufferer.thrust_loss
      << YAML::Key << "kv_omega_n_per_mps" << YAML::Value << c.sufferer.kv_omega_n_per_mps
      << YAML::Key << "rotor_drag_n_per_mps" << YAML::Value << c.sufferer.rotor_drag_n_per_mps << YAML::EndMap;
    o << YAML::Key << "neighbour" << YAML::Value;
    vehicle(c.neighbour);
    o << YAML::Key << "stand" << YAML::Value << YAML::BeginMap
      << YAML::Key << "height_m" << YAML::Value << c.stand.height_m
      << YAML::Key << "lateral_radius_m" << YAML::Value << c.stand.lateral_radius_m
      << YAML::Key << "counts_per_newton" << YAML::Value << c.stand.counts_per_newton
      << YAML::Key << "offset_sigma_counts" << YAML::Value << c.stand.offset_sigma_counts
      << YAML::Key << "rate_hz" << YAML::Value << c.stand.rate_hz
      << YAML::Key << "rate_skew" << YAML::Value << c.stand.rate_skew
      << YAML::Key << "noise_n" << YAML::Value << c.stand.noise_n
      << YAML::Key << "tare_s" << YAML::Value << c.stand.tare_s << YAML::EndMap;
    o << YAML::Key << "turbulence" << YAML::Value << YAML::BeginMap
      << YAML::Key << "enabled" << YAML::Value << c.turbulence.enabled
      << YAML::Key << "intensity" << YAML::Value << c.turbulence.intensity
      << YAML::Key << "time_scale_s" << YAML::Value << c.turbulence.time_scale_s
      << YAML::Key << "lateral_intensity" << YAML::Value << c.turbulence.lateral_intensity
      << YAML::Key << "lateral_time_scale_s" << YAML::Value << c.turbulence.lateral_time_scale_s << YAML::EndMap;
    o << YAML::Key << "dynamics" << YAML::Value << YAML::BeginMap
      << YAML::Key << "natural_frequency_rad_s" << YAML::Value << c.dynamics.natural_frequency_rad_s
      << YAML::Key << "damping" << YAML::Value << c.dynamics.damping
      << YAML::Key << "hover_noise_m" << YAML::Value << c.dynamics.hover_noise_m
      << YAML::Key << "hover_noise_time_s" << YAML::Value << c.dynamics.hover_noise_time_s
      << YAML::Key << "rate_hz" << YAML::Value << c.dynamics.rate_hz << YAML::EndMap;
    o << YAML::Key << "mocap" << YAML::Value << YAML::BeginMap
      << YAML::Key << "rate_hz" << YAML::Value << c.mocap.rate_hz
      << YAML::Key << "noise_m" << YAML::Value << c.mocap.noise_m << YAML::EndMap;
    o << YAML::Key << "effects" << YAML::Value << YAML::BeginMap;
    for (const auto* t : effect_types()) t->write(o, c.effects);
    o << YAML::EndMap << YAML::EndMap;
    return std::string(o.c_str()) + "\n";
}

}  // namespace dw::physics
