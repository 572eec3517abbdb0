#include "swarm_planner/px4_config.hpp"

#include <numbers>
#include <set>

#include "core/config.hpp"
#include "core/keys.hpp"
#include "core/log.hpp"

namespace dw::planner {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;

void version_key(KeyVisitor& k, dds::Px4Version& version) {
    std::string name(dds::px4_version(version).name);
    k.text("version", name);
    const auto found = dds::find_px4_version(name);
    k.require(found.has_value(), "version", dds::unknown_px4_version_problem(name));
    if (found) version = *found;
}

// One vehicle's keys; `ids` collects the system ids so far (each PX4 needs its own).
void vehicle_keys(KeyVisitor& k, Px4Vehicle& v, std::set<int>& ids) {
    k.text("namespace", v.ns);
    k.integer("system_id", v.system_id, kSystemIdRange);
    k.numbers("origin_m", std::span<double>(v.origin.data(), 3), kOriginRange,
              "expected [north, east, down] in metres");
    double heading_deg = v.heading_rad / kDegree;
    k.number("heading_deg", heading_deg, kHeadingRange);
    v.heading_rad = heading_deg * kDegree;
    k.require(ids.insert(v.system_id).second, "system_id", "used by two vehicles (each PX4 needs its own MAV_SYS_ID)");
}

// The file's keys; `o.vehicles` holds the plan's vehicles with their defaults.
void px4_keys(KeyVisitor& k, Px4Options& o) {
    version_key(k, o.version);
    k.enumeration("odometry", o.odometry, kOdometryByNames, "odometry feed");
    k.number("odometry_hz", o.odometry_hz, kOdometryRateRange);
    k.number("position_std_m", o.position_std_m, kStdRange);
    k.number("orientation_std_rad", o.orientation_std_rad, kStdRange);
    k.number("velocity_std_mps", o.velocity_std_mps, kStdRange);
    k.number("answer_timeout_s", o.answer_timeout_s, kAnswerTimeoutRange);
    k.integer("attempts", o.attempts, kAttemptsRange);
    k.number("status_timeout_s", o.status_timeout_s, kStatusTimeoutRange);
    k.number("land_timeout_s", o.land_timeout_s, kLandTimeoutRange);
    k.number("estimator_timeout_s", o.estimator_timeout_s, kEstimatorTimeoutRange);
    k.number("takeoff_ramp_s", o.takeoff_ramp_s, kTakeoffRampRange);
    k.enumeration("ground", o.ground, kGroundFromNames, "ground");
    k.require(o.ground != GroundFrom::estimate || o.odometry == OdometryBy::off, "ground",
              "estimate needs odometry: off (a PX4 fed the lab's odometry already works in the lab's frame)");
    k.require(k.has("vehicles"), "vehicles", "expected a mapping from each of the plan's vehicles to its PX4 settings");
    std::set<int> ids;
    const auto vehicles = [&](KeyVisitor& vs) {
        for (auto& v : o.vehicles) {
            vs.require(vs.has(v.name), v.name, "no entry for the plan's vehicle " + v.name);
            vs.section(v.name, [&](KeyVisitor& s) { vehicle_keys(s, v, ids); });
        }
    };
    k.section("vehicles", vehicles, "not a vehicle of this plan");
}

}  // namespace

Px4Options default_px4_options(const std::vector<std::string>& plan_vehicles) {
    Px4Options o;
    for (std::size_t i = 0; i < plan_vehicles.size(); ++i)
        o.vehicles.push_back({plan_vehicles[i], plan_vehicles[i], static_cast<int>(i + 1)});
    return o;
}

Px4Options load_px4_options(const std::string& path, const std::vector<std::string>& plan_vehicles) {
    Px4Options o = default_px4_options(plan_vehicles);
    read_keys(load_yaml_file(path, "config"), path, [&](KeyVisitor& k) { px4_keys(k, o); });
    return o;
}

}  // namespace dw::planner
