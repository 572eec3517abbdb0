#include "swarm_planner/vehicle_link.hpp"

#include "core/log.hpp"
#include "core/names.hpp"
#include "dds/time.hpp"
#include "swarm_planner/px4_link.hpp"

namespace dw::planner {

LinkKind parse_link(std::string_view name, std::string_view option) {
    if (const auto i = find_name(kLinkNames, name)) return static_cast<LinkKind>(*i);
    throw InputError(log::cat(option, ": ", unknown_name_problem("vehicle link", name, kLinkNames)));
}

void VehicleLink::send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) {
    passed_.resize(sps.size());
    said_.resize(sps.size(), false);
    std::vector<std::optional<physics::Setpoint>> out(sps.size());
    for (std::size_t i = 0; i < sps.size(); ++i) {
        const bool finite = is_finite(sps[i]);
        if (finite && fence_.contains(sps[i].position, Geofence::kTolerance_m)) {
            out[i] = passed_[i] = sps[i];
            continue;
        }
        ++refused_;
        if (passed_[i]) {
            out[i] = *passed_[i];
            out[i]->velocity = out[i]->acceleration = physics::Vec3::Zero();
        }
        if (!said_[i]) {
            said_[i] = true;
            const auto& x = sps[i].position;
            log::error("vehicle link: vehicle ", i + 1, "'s setpoint refused at the last gate (",
                       finite ? log::cat("outside the geofence: ", x.x(), ", ", x.y(), ", ", x.z()) : "not finite",
                       "); it ", passed_[i] ? "holds its last setpoint that passed" : "is sent nothing");
        }
    }
    deliver(out, now_ns);
}

SimLink::SimLink(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id)
    : vehicles_(std::move(vehicles)), run_id_(std::move(run_id)), writer_(p, dds::topics::vehicle_setpoint) {}

void SimLink::deliver(const std::vector<std::optional<physics::Setpoint>>& gated, Nanos now_ns) {
    for (std::size_t i = 0; i < gated.size(); ++i) {
        if (!gated[i]) continue;
        const physics::Setpoint& sp = *gated[i];
        msg::VehicleSetpoint m;
        m.header().stamp(dds::to_msg(now_ns));
        m.header().run_id(run_id_);
        m.vehicle_id(vehicles_[i]);
        m.position_m().x(sp.position.x());
        m.position_m().y(sp.position.y());
        m.position_m().z(sp.position.z());
        m.velocity_mps().x(sp.velocity.x());
        m.velocity_mps().y(sp.velocity.y());
        m.velocity_mps().z(sp.velocity.z());
        m.acceleration_mps2().x(sp.acceleration.x());
        m.acceleration_mps2().y(sp.acceleration.y());
        m.acceleration_mps2().z(sp.acceleration.z());
        m.yaw_rad(sp.yaw_rad);
        writer_.write(m);
    }
}

std::unique_ptr<VehicleLink> make_link(LinkKind kind, dds::Participant& p, const std::vector<std::string>& vehicles,
                                       const std::string& run_id, const Px4Options& px4) {
    switch (kind) {
        case LinkKind::sim: return std::make_unique<SimLink>(p, vehicles, run_id);
        case LinkKind::px4: return make_px4_link(p, px4);
    }
    throw RuntimeError("unknown vehicle link");
}

}  // namespace dw::planner
