#pragma once
// The `sim` source: an emulated NatNet server on loopback whose bodies are simulated vehicles
// following the planner's setpoints (vehicles/setpoint) with lag and hover noise, and the
// sufferer on the stand. The bridge reads it with the same NatNet client as a real Motive.
#include <map>
#include <memory>
#include <mutex>

#include "dds/endpoint.hpp"
#include "mocap_bridge/emulator.hpp"
#include "physics/vehicle.hpp"

namespace dw::natnet {

class SimSource {
public:
    SimSource(dds::Participant& p, const std::vector<std::string>& names, double rate_hz);
    std::uint16_t port() const { return emulator_->port(); }

private:
    BodyPose pose(int body, double t);

    std::vector<std::string> names_;
    physics::PhysicsConfig physics_;
    std::mutex mutex_;
    std::map<std::string, physics::Setpoint> setpoints_;
    std::vector<physics::SimVehicle> vehicles_;
    double t_ = 0;
    dds::Reader<msg::VehicleSetpoint> reader_;
    std::unique_ptr<NatNetEmulator> emulator_;
};

}  // namespace dw::natnet
