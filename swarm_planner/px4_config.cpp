#include "swarm_planner/px4_config.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "core/config.hpp"
#include "core/log.hpp"

namespace dw::planner {
namespace {

const std::set<std::string> kTopKeys{"version", "odometry", "odometry_hz", "position_std_m", "orientation_std_rad",
                                     "velocity_std_mps", "answer_timeout_s", "attempts", "status_timeout_s", "vehicles"};
const std::set<std::string> kVehicleKeys{"namespace", "system_id", "origin_m", "heading_deg"};

Px4Vehicle read_vehicle(const ConfigFile& c, const std::string& name, std::size_t index) {
    const std::string at = "vehicles." + name;
    if (!c.at(at).IsMap()) c.fail(at, "expected a mapping (namespace, system_id, origin_m, heading_deg)");
    c.require_keys(at, kVehicleKeys);
    Px4Vehicle v{name, name, static_cast<int>(index + 1)};
    if (auto ns = c.get_string(at + ".namespace")) v.ns = *ns;
    if (auto id = c.get_int(at + ".system_id", kSystemIdRange)) v.system_id = static_cast<int>(*id);
    if (auto h = c.get_double(at + ".heading_deg", kHeadingRange)) v.heading_rad = *h * std::numbers::pi / 180.0;
    if (auto o = c.get_strings(at + ".origin_m")) {
        if (o->size() != 3) c.fail(at + ".origin_m", "expected [north, east, down] in metres");
        for (int k = 0; k < 3; ++k) {
            try {
                v.origin[k] = require_in(parse_number((*o)[static_cast<std::size_t>(k)], "origin_m"), kOriginRange, "origin_m");
            } catch (const InputError& e) {
                c.fail(at + ".origin_m", e.what());
            }
        }
    }
    return v;
}

void read_top(const ConfigFile& c, Px4Options& o) {
    if (auto v = c.get_string("version")) {
        try {
            o.version = dds::parse_px4_version(*v, "");
        } catch (const InputError& e) {
            c.fail("version", e.what());
        }
    }
    if (auto v = c.get_bool("odometry")) o.odometry = *v;
    if (auto v = c.get_double("odometry_hz", kOdometryRateRange)) o.odometry_hz = *v;
    if (auto v = c.get_double("position_std_m", kStdRange)) o.position_std_m = *v;
    if (auto v = c.get_double("orientation_std_rad", kStdRange)) o.orientation_std_rad = *v;
    if (auto v = c.get_double("velocity_std_mps", kStdRange)) o.velocity_std_mps = *v;
    if (auto v = c.get_double("answer_timeout_s", kAnswerTimeoutRange)) o.answer_timeout_s = *v;
    if (auto v = c.get_int("attempts", kAttemptsRange)) o.attempts = static_cast<int>(*v);
    if (auto v = c.get_double("status_timeout_s", kStatusTimeoutRange)) o.status_timeout_s = *v;
}

}  // namespace

Px4Options default_px4_options(const std::vector<std::string>& plan_vehicles) {
    Px4Options o;
    for (std::size_t i = 0; i < plan_vehicles.size(); ++i) o.vehicles.push_back({plan_vehicles[i], plan_vehicles[i], static_cast<int>(i + 1)});
    return o;
}

Px4Options load_px4_options(const std::string& path, const std::vector<std::string>& plan_vehicles) {
    const ConfigFile c = ConfigFile::load(path);
    c.require_keys("", kTopKeys);
    Px4Options o;
    read_top(c, o);
    const YAML::Node vehicles = c.at("vehicles");
    if (!vehicles || !vehicles.IsMap()) c.fail("vehicles", "expected a mapping from each of the plan's vehicles to its PX4 settings");
    for (const auto& kv : vehicles) {
        const std::string name = kv.first.Scalar();
        if (std::find(plan_vehicles.begin(), plan_vehicles.end(), name) == plan_vehicles.end())
            c.fail("vehicles." + name, "not a vehicle of this plan (" + log::join(plan_vehicles) + ")");
    }
    std::set<int> ids;
    for (std::size_t i = 0; i < plan_vehicles.size(); ++i) {
        if (!c.at("vehicles." + plan_vehicles[i])) c.fail("vehicles", "no entry for the plan's vehicle " + plan_vehicles[i]);
        o.vehicles.push_back(read_vehicle(c, plan_vehicles[i], i));
        if (!ids.insert(o.vehicles.back().system_id).second)
            c.fail("vehicles." + plan_vehicles[i] + ".system_id", "used by two vehicles (each PX4 needs its own MAV_SYS_ID)");
    }
    return o;
}

}  // namespace dw::planner
