#include "swarm_planner/vehicle_link.hpp"

#include <cmath>

#include "core/log.hpp"
#include "core/names.hpp"
#include "dds/time.hpp"
#include "swarm_planner/px4_link.hpp"

namespace dw::planner {

LinkKind parse_link(std::string_view name, std::string_view option) {
    if (const auto i = find_name(kLinkNames, name)) return static_cast<LinkKind>(*i);
    throw InputError(log::cat(option, ": ", unknown_name_problem("vehicle link", name, kLinkNames)));
}

bool VehicleLink::admissible(const physics::Setpoint& sp) const {
    if (!is_finite(sp)) return false;
    physics::Vec3 x = sp.position;
    if (descending_) x.z() = std::min(x.z(), fence_.d_max);  // below the floor: where a landing ends
    return fence_.contains(x, Geofence::kTolerance_m);
}

physics::Setpoint VehicleLink::only_down(std::size_t i, physics::Setpoint sp) {
    double lowest = sp.position.z();
    if (delivered_d_[i]) lowest = std::max(lowest, *delivered_d_[i]);
    if (const auto d = down_of(i); d && std::isfinite(*d)) lowest = std::max(lowest, *d);
    if (lowest > sp.position.z()) {  // held where it is: at rest vertically
        sp.position.z() = lowest;
        sp.velocity.z() = sp.acceleration.z() = 0;
    }
    sp.velocity.z() = std::max(sp.velocity.z(), 0.0);  // D grows downwards: nothing that lifts
    return sp;
}

void VehicleLink::send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) {
    passed_.resize(sps.size());
    delivered_d_.resize(sps.size());
    said_.resize(sps.size(), false);
    std::vector<std::optional<physics::Setpoint>> out(sps.size());
    for (std::size_t i = 0; i < sps.size(); ++i) {
        if (admissible(sps[i])) {
            out[i] = passed_[i] = sps[i];
        } else {
            ++refused_;
            if (passed_[i]) {
                out[i] = *passed_[i];
                out[i]->velocity = out[i]->acceleration = physics::Vec3::Zero();
            }
            if (!said_[i]) {
                said_[i] = true;
                const auto& x = sps[i].position;
                log::error("vehicle link: vehicle ", i + 1, "'s setpoint refused at the last gate (",
                           is_finite(sps[i]) ? log::cat("outside the geofence: ", x.x(), ", ", x.y(), ", ", x.z())
                                             : "not finite",
                           "); it ", passed_[i] ? "holds its last setpoint that passed" : "is sent nothing");
            }
        }
        if (out[i] && descending_) out[i] = only_down(i, *out[i]);
        if (out[i]) delivered_d_[i] = out[i]->position.z();
    }
    deliver(out, now_ns);
}

SetpointWriter::SetpointWriter(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id)
    : vehicles_(std::move(vehicles)), run_id_(std::move(run_id)), writer_(p, dds::topics::vehicle_setpoint) {}

void SetpointWriter::write(const std::vector<std::optional<physics::Setpoint>>& gated, Nanos now_ns) {
    for (std::size_t i = 0; i < gated.size() && i < vehicles_.size(); ++i) {
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

VehicleHeights::VehicleHeights(dds::Participant& p, const std::vector<std::string>& vehicles)
    : p_(p),
      vehicles_(vehicles),
      reader_(p, dds::topics::vehicle_state, [this](const msg::VehicleState& s, const dds::SampleMeta&) {
          // A lost body's state holds a pose it was seen at, or none (zeros): no height (issue 70: a
          // lost state at D = 0 made a landing vehicle's gate drop its setpoint 1.4 m to the floor).
          if (!s.tracking_valid()) return;
          const double d = s.position_m().z();
          if (!physics::plausible_position(physics::Vec3(s.position_m().x(), s.position_m().y(), d))) return;
          if (std::find(vehicles_.begin(), vehicles_.end(), s.vehicle_id()) == vehicles_.end()) return;  // not ours
          std::lock_guard lock(mutex_);
          latest_[s.vehicle_id()] = {d, p_.clock().monotonic_ns()};
      }) {}

std::optional<double> VehicleHeights::down_of(std::size_t i) const {
    if (i >= vehicles_.size()) return std::nullopt;
    std::lock_guard lock(mutex_);
    const auto it = latest_.find(vehicles_[i]);
    if (it == latest_.end() || !(to_seconds(p_.clock().monotonic_ns() - it->second.second) <= kPositionFreshS))
        return std::nullopt;
    return it->second.first;
}

SimLink::SimLink(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id)
    : writer_(p, vehicles, std::move(run_id)), heights_(p, vehicles) {}

void SimLink::deliver(const std::vector<std::optional<physics::Setpoint>>& gated, Nanos now_ns) {
    writer_.write(gated, now_ns);
}

std::unique_ptr<VehicleLink> make_link(LinkKind kind, dds::Participant& p, const std::vector<std::string>& vehicles,
                                       const std::string& run_id, const Px4Options& px4) {
    switch (kind) {
        case LinkKind::sim: return std::make_unique<SimLink>(p, vehicles, run_id);
        case LinkKind::px4: return make_px4_link(p, px4, run_id);
    }
    throw RuntimeError("unknown vehicle link");
}

}  // namespace dw::planner
