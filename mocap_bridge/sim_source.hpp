#pragma once
// The `sim` source: an emulated NatNet server on loopback whose bodies are simulated vehicles
// following the planner's setpoints (vehicles/setpoint) with lag and hover noise, and the
// sufferer on the stand. The bridge reads it with the same NatNet client as a real Motive.
#include <map>
#include <memory>
#include <mutex>
#include <optional>

#include "core/numbers.hpp"

#include "dds/endpoint.hpp"
#include "mocap_bridge/emulator.hpp"
#include "physics/vehicle.hpp"

namespace dw::natnet {

// A fault injected into one simulated vehicle, `after_s` seconds (simulated) after its first
// setpoint: `stuck`, it stops following its setpoints (the planner sees a tracking error); `jump`,
// motion capture reports it kJumpDistance_m north of where it is (a geofence breach).
struct SimFault {
    enum class Kind { stuck, jump };
    static constexpr const char* kKindNames[] = {"stuck", "jump"};  // Kind's values in order
    Kind kind = Kind::stuck;
    std::string vehicle;
    double after_s = 0;
};
inline constexpr double kJumpDistance_m = 10.0;
inline constexpr Range kFaultAfterRange{0, 3600, "s"};
// "stuck:v1:8" or "jump:v2:5.5"; throws dw::InputError naming what is wrong.
SimFault parse_sim_fault(const std::string& text);

class SimSource {
public:
    SimSource(dds::Participant& p, const std::vector<std::string>& names, double rate_hz,
              std::optional<SimFault> fault = {}, const Hostility& hostile = {});
    std::uint16_t port() const { return emulator_->port(); }

private:
    BodyPose pose(int body, double t);
    bool fault_active(const std::string& vehicle, SimFault::Kind kind) const;  // under mutex_

    std::vector<std::string> names_;
    physics::PhysicsConfig physics_;
    std::mutex mutex_;
    std::map<std::string, physics::Setpoint> setpoints_;
    std::vector<physics::SimVehicle> vehicles_;
    double t_ = 0;
    std::optional<SimFault> fault_;
    std::optional<double> fault_clock_start_;  // simulated time of the faulty vehicle's first setpoint
    dds::Reader<msg::VehicleSetpoint> reader_;
    std::unique_ptr<NatNetEmulator> emulator_;
};

}  // namespace dw::natnet
