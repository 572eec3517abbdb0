#include "mocap_bridge/sim_source.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "core/names.hpp"

namespace dw::natnet {

SimFault parse_sim_fault(const std::string& text) {
    const auto a = text.find(':'), b = text.rfind(':');
    const std::string what = "--sim-fault '" + text + "'";
    if (a == std::string::npos || a == b || a == 0 || b == a + 1)
        throw InputError(what + ": expected KIND:VEHICLE:AFTER_S (stuck:v1:8)");
    SimFault f;
    const std::string kind = text.substr(0, a);
    const auto k = find_name(SimFault::kKindNames, kind);
    if (!k) throw InputError(what + ": " + unknown_name_problem("fault", kind, SimFault::kKindNames));
    f.kind = static_cast<SimFault::Kind>(*k);
    f.vehicle = text.substr(a + 1, b - a - 1);
    f.after_s = require_in(parse_number(text.substr(b + 1), what), kFaultAfterRange, what);
    return f;
}

SimSource::SimSource(dds::Participant& p, const std::vector<std::string>& names, double rate_hz,
                     std::optional<SimFault> fault, const Hostility& hostile)
    : names_(names),
      fault_(std::move(fault)),
      reader_(p, dds::topics::vehicle_setpoint, [this](const msg::VehicleSetpoint& s, const dds::SampleMeta&) {
          physics::Setpoint sp;
          sp.position = physics::Vec3(s.position_m().x(), s.position_m().y(), s.position_m().z());
          sp.velocity = physics::Vec3(s.velocity_mps().x(), s.velocity_mps().y(), s.velocity_mps().z());
          sp.acceleration =
              physics::Vec3(s.acceleration_mps2().x(), s.acceleration_mps2().y(), s.acceleration_mps2().z());
          sp.yaw_rad = s.yaw_rad();
          // A simulated vehicle, like a real one, must never be driven by a non-finite setpoint.
          if (!physics::is_finite(sp)) return;
          if (std::find(names_.begin(), names_.end(), s.vehicle_id()) == names_.end()) return;  // not simulated here
          std::lock_guard lock(mutex_);
          if (fault_ && s.vehicle_id() == fault_->vehicle && !fault_clock_start_) fault_clock_start_ = t_;
          if (fault_active(s.vehicle_id(), SimFault::Kind::stuck)) return;  // it no longer follows
          setpoints_[s.vehicle_id()] = sp;
      }) {
    if (fault_ && std::find(names_.begin() + 1, names_.end(), fault_->vehicle) == names_.end())
        throw InputError("--sim-fault: no simulated vehicle named '" + fault_->vehicle + "'");
    physics::Rng rng(1);
    for (std::size_t i = 1; i < names_.size(); ++i) {
        // Parked on the floor west of the stand until setpoints arrive.
        const physics::Vec3 start(-1.0 + 0.7 * static_cast<double>(i - 1), -2.4, 0.0);
        vehicles_.emplace_back(physics_.dynamics, physics_.gravity_m_s2, start, rng.split());
        setpoints_[names_[i]].position = start;
    }
    EmulatorOptions o;
    o.port = 0;
    o.rate_hz = rate_hz;
    o.names = names_;
    o.motion = [this](int body, double t) { return pose(body, t); };
    o.hostile = hostile;
    emulator_ = std::make_unique<NatNetEmulator>(o);
}

bool SimSource::fault_active(const std::string& vehicle, SimFault::Kind kind) const {
    return fault_ && fault_->kind == kind && fault_->vehicle == vehicle && fault_clock_start_ &&
           t_ >= *fault_clock_start_ + fault_->after_s;
}

BodyPose SimSource::pose(int body, double t) {
    std::lock_guard lock(mutex_);
    if (body == 0) {
        BodyPose p;
        p.ned = {0, 0, -physics_.stand.height_m};
        return p;
    }
    if (body == 1) {  // once per frame: advance every vehicle to t at the dynamics' rate
        const double dt = 1.0 / physics_.dynamics.rate_hz;
        while (t_ + dt <= t) {
            for (std::size_t i = 0; i < vehicles_.size(); ++i) vehicles_[i].step(setpoints_[names_[i + 1]], dt);
            t_ += dt;
        }
    }
    const auto& s = vehicles_[static_cast<std::size_t>(body - 1)].state();
    BodyPose p;
    // The dynamics step at their own rate: the pose at t itself, carried on from the last step.
    const physics::Vec3 at = s.position + s.velocity * (t - t_);
    p.ned = {at.x(), at.y(), at.z()};
    if (fault_active(names_[static_cast<std::size_t>(body)], SimFault::Kind::jump)) p.ned[0] += kJumpDistance_m;
    p.q_ned = {s.orientation.w(), s.orientation.x(), s.orientation.y(), s.orientation.z()};
    return p;
}

}  // namespace dw::natnet
