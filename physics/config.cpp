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

namespace dw::physics {
namespace {

// Reads one YAML mapping strictly: every key must be consumed, values are checked.
class Section {
public:
    Section(const YAML::Node& node, std::string path, const std::string& file)
        : node_(node), path_(std::move(path)), file_(file) {
        if (node_ && !node_.IsNull() && !node_.IsMap()) fail(node_, "expected a mapping of keys");
    }
    ~Section() noexcept(false) {
        if (std::uncaught_exceptions() > 0 || !node_ || node_.IsNull()) return;
        for (const auto& kv : node_) {
            const std::string key = kv.first.Scalar();
            if (!used_.count(key)) fail(kv.first, log::cat("unknown key '", key, "'"), key);
        }
    }
    YAML::Node get(const std::string& key) {
        used_.insert(key);
        if (!node_ || node_.IsNull()) return YAML::Node(YAML::NodeType::Undefined);
        const YAML::Node& view = node_;
        return view[key];
    }
    void number(const std::string& key, double& out, double min, double max) {
        const YAML::Node n = get(key);
        if (!n) return;
        double v = 0;
        if (!n.IsScalar() || !YAML::convert<double>::decode(n, v)) fail(n, "expected a number", key);
        const Range range{min, max};
        if (!range.contains(v)) fail(n, range_problem(v, range), key);
        out = v;
    }
    void integer(const std::string& key, int& out, int min, int max) {
        double v = out;
        number(key, v, min, max);
        if (v != std::floor(v)) fail(get(key), "expected a whole number", key);
        out = static_cast<int>(v);
    }
    void flag(const std::string& key, bool& out) {
        const YAML::Node n = get(key);
        if (!n) return;
        bool v = false;
        if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) fail(n, "expected true or false", key);
        out = v;
    }
    std::string text(const std::string& key, const std::string& fallback) {
        const YAML::Node n = get(key);
        if (!n) return fallback;
        if (!n.IsScalar()) fail(n, "expected a word", key);
        return n.Scalar();
    }
    Section sub(const std::string& key) { return Section(get(key), path_.empty() ? key : path_ + "." + key, file_); }
    [[noreturn]] void fail(const YAML::Node& n, const std::string& what, const std::string& key = "") const {
        const std::string where = path_.empty() ? key : (key.empty() ? path_ : path_ + "." + key);
        if (n && n.Mark().line >= 0) {
            throw InputError(log::cat(file_, ":", n.Mark().line + 1, ":", n.Mark().column + 1, ": ", where, ": ", what));
        }
        throw InputError(log::cat(file_, ": ", where, ": ", what));
    }

private:
    YAML::Node node_;
    std::string path_;
    const std::string& file_;
    std::set<std::string> used_;
};

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

PhysicsConfig parse_physics(const std::string& yaml, const std::string& file) {
    const YAML::Node root = load_yaml(yaml, file);
    PhysicsConfig c;
    Section top(root, "", file);
    const std::string format = top.text("format", "downwash-physics/1");
    if (format != "downwash-physics/1") top.fail(top.get("format"), "expected downwash-physics/1", "format");
    top.number("air_density_kg_m3", c.air_density_kg_m3, 0.5, 2.0);
    top.number("gravity_m_s2", c.gravity_m_s2, 1.0, 20.0);
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
    }
    read_vehicle(top.sub("neighbour"), c.neighbour);
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
    {
        Section e = top.sub("effects");
        auto& x = c.effects;
        { Section s = e.sub("clock_offset"); s.flag("enabled", x.clock_offset.enabled); s.number("offset_s", x.clock_offset.offset_s, -10, 10); }
        { Section s = e.sub("sensor_lag"); s.flag("enabled", x.sensor_lag.enabled); s.number("tau_s", x.sensor_lag.tau_s, 0, 10); }
        { Section s = e.sub("wake_transport"); s.flag("enabled", x.wake_transport.enabled); s.number("delay_scale", x.wake_transport.delay_scale, 0, 10); }
        {
            Section s = e.sub("position_offset");
            s.flag("enabled", x.position_offset.enabled);
            const YAML::Node n = s.get("offset_m");
            if (n) {
                if (!n.IsSequence() || n.size() != 3) s.fail(n, "expected [n, e, d] in metres", "offset_m");
                const Range range{-10, 10, "m"};
                for (std::size_t i = 0; i < 3; ++i) {
                    double v = 0;
                    if (!YAML::convert<double>::decode(n[i], v)) s.fail(n, "expected [n, e, d] in metres", "offset_m");
                    if (!range.contains(v)) s.fail(n, range_problem(v, range), "offset_m");
                    x.position_offset.offset_m[i] = v;
                }
            }
        }
        { Section s = e.sub("force_scale"); s.flag("enabled", x.force_scale.enabled); s.number("scale", x.force_scale.scale, 0, 10); }
        {
            Section s = e.sub("cell_crosstalk");
            s.flag("enabled", x.cell_crosstalk.enabled);
            for (auto [key, out] : {std::pair<const char*, int*>{"from", &x.cell_crosstalk.from}, {"to", &x.cell_crosstalk.to}}) {
                const std::string name = s.text(key, axis_name(*out));
                const int idx = axis_index(name);
                if (idx < 0) s.fail(s.get(key), log::cat("unknown axis '", name, "' (expected f_n, f_e, f_d, m_roll, m_pitch or m_yaw)"), key);
                *out = idx;
            }
            s.number("coefficient", x.cell_crosstalk.coefficient, -1, 1);
        }
        {
            Section s = e.sub("jet_merging");
            s.flag("enabled", x.jet_merging.enabled);
            s.number("contraction", x.jet_merging.contraction, 0.2, 2);
            s.number("onset", x.jet_merging.onset, 0, 10);
            s.number("full", x.jet_merging.full, 0, 10);
            if (x.jet_merging.full <= x.jet_merging.onset) s.fail(s.get("full"), "must be greater than onset", "full");
        }
        {
            Section s = e.sub("floor_recirculation");
            s.flag("enabled", x.floor_recirculation.enabled);
            s.number("coefficient", x.floor_recirculation.coefficient, 0, 1);
            s.number("length_m", x.floor_recirculation.length_m, 0.01, 100);
        }
        {
            Section s = e.sub("body_drag");
            s.flag("enabled", x.body_drag.enabled);
            s.number("cda_h_m2", x.body_drag.cda_h_m2, 0, 10);
            s.number("cda_v_m2", x.body_drag.cda_v_m2, 0, 10);
        }
        { Section s = e.sub("ground_effect"); s.flag("enabled", x.ground_effect.enabled); s.number("coefficient", x.ground_effect.coefficient, 0, 10); }
    }
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
    const auto& x = c.effects;
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
      << YAML::Key << "kv_omega_n_per_mps" << YAML::Value << c.sufferer.kv_omega_n_per_mps << YAML::EndMap;
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
      << YAML::Key << "time_scale_s" << YAML::Value << c.turbulence.time_scale_s << YAML::EndMap;
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
    o << YAML::Key << "clock_offset" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.clock_offset.enabled << YAML::Key << "offset_s" << YAML::Value << x.clock_offset.offset_s << YAML::EndMap;
    o << YAML::Key << "sensor_lag" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.sensor_lag.enabled << YAML::Key << "tau_s" << YAML::Value << x.sensor_lag.tau_s << YAML::EndMap;
    o << YAML::Key << "wake_transport" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.wake_transport.enabled << YAML::Key << "delay_scale" << YAML::Value << x.wake_transport.delay_scale << YAML::EndMap;
    o << YAML::Key << "position_offset" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.position_offset.enabled << YAML::Key << "offset_m" << YAML::Value << YAML::Flow << YAML::BeginSeq
      << x.position_offset.offset_m[0] << x.position_offset.offset_m[1] << x.position_offset.offset_m[2]
      << YAML::EndSeq << YAML::EndMap;
    o << YAML::Key << "force_scale" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.force_scale.enabled << YAML::Key << "scale" << YAML::Value << x.force_scale.scale << YAML::EndMap;
    o << YAML::Key << "cell_crosstalk" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.cell_crosstalk.enabled << YAML::Key << "from" << YAML::Value << axis_name(x.cell_crosstalk.from)
      << YAML::Key << "to" << YAML::Value << axis_name(x.cell_crosstalk.to) << YAML::Key << "coefficient"
      << YAML::Value << x.cell_crosstalk.coefficient << YAML::EndMap;
    o << YAML::Key << "jet_merging" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.jet_merging.enabled << YAML::Key << "contraction" << YAML::Value << x.jet_merging.contraction
      << YAML::Key << "onset" << YAML::Value << x.jet_merging.onset << YAML::Key << "full" << YAML::Value
      << x.jet_merging.full << YAML::EndMap;
    o << YAML::Key << "floor_recirculation" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled"
      << YAML::Value << x.floor_recirculation.enabled << YAML::Key << "coefficient" << YAML::Value
      << x.floor_recirculation.coefficient << YAML::Key << "length_m" << YAML::Value
      << x.floor_recirculation.length_m << YAML::EndMap;
    o << YAML::Key << "body_drag" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.body_drag.enabled << YAML::Key << "cda_h_m2" << YAML::Value << x.body_drag.cda_h_m2 << YAML::Key
      << "cda_v_m2" << YAML::Value << x.body_drag.cda_v_m2 << YAML::EndMap;
    o << YAML::Key << "ground_effect" << YAML::Value << YAML::BeginMap << YAML::Key << "enabled" << YAML::Value
      << x.ground_effect.enabled << YAML::Key << "coefficient" << YAML::Value << x.ground_effect.coefficient << YAML::EndMap;
    o << YAML::EndMap << YAML::EndMap;
    return std::string(o.c_str()) + "\n";
}

}  // namespace dw::physics
