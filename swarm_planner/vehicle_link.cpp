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

SimLink::SimLink(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id)
    : vehicles_(std::move(vehicles)), run_id_(std::move(run_id)), writer_(p, dds::topics::vehicle_setpoint) {}

void SimLink::send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) {
    for (std::size_t i = 0; i < sps.size(); ++i) {
        msg::VehicleSetpoint m;
        m.header().stamp(dds::to_msg(now_ns));
        m.header().run_id(run_id_);
        m.vehicle_id(vehicles_[i]);
        m.position_m().x(sps[i].position.x());
        m.position_m().y(sps[i].position.y());
        m.position_m().z(sps[i].position.z());
        m.velocity_mps().x(sps[i].velocity.x());
        m.velocity_mps().y(sps[i].velocity.y());
        m.velocity_mps().z(sps[i].velocity.z());
        m.acceleration_mps2().x(sps[i].acceleration.x());
        m.acceleration_mps2().y(sps[i].acceleration.y());
        m.acceleration_mps2().z(sps[i].acceleration.z());
        m.yaw_rad(sps[i].yaw_rad);
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
