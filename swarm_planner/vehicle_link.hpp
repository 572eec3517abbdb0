#pragma once
// How the planner's setpoints reach the vehicles, behind one interface: `sim` (the lab's
// vehicles/setpoint topic, which the simulated vehicles follow) and `px4` (PX4 through its
// uXRCE-DDS bridge on the same domain: OffboardControlMode + TrajectorySetpoint on
// rt/<vehicle>/fmu/in/..., VehicleCommand to switch to offboard, arm and land).
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "dds/endpoint.hpp"
#include "dds/px4.hpp"
#include "physics/vehicle.hpp"

namespace dw::planner {

class VehicleLink {
public:
    virtual ~VehicleLink() = default;
    virtual void send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) = 0;
    virtual void start() {}  // before take-off
    virtual void land() {}   // after the landing setpoints
};

class SimLink final : public VehicleLink {
public:
    SimLink(dds::Participant& p, std::vector<std::string> vehicles, std::string run_id);
    void send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) override;

private:
    std::vector<std::string> vehicles_;
    std::string run_id_;
    dds::Writer<msg::VehicleSetpoint> writer_;
};

class Px4Link final : public VehicleLink {
public:
    // `home_ned[i]`: where vehicle i's PX4 local origin is in the lab's NED frame.
    Px4Link(dds::Participant& p, const std::vector<std::string>& vehicles, std::vector<physics::Vec3> home_ned);
    void send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) override;
    void start() override;  // DO_SET_MODE offboard, then arm
    void land() override;   // NAV_LAND

private:
    struct Vehicle {
        std::string traj_topic, mode_topic, cmd_topic;
        std::unique_ptr<dds::Writer<px4_msgs::msg::dds_::TrajectorySetpoint_>> traj;
        std::unique_ptr<dds::Writer<px4_msgs::msg::dds_::OffboardControlMode_>> mode;
        std::unique_ptr<dds::Writer<px4_msgs::msg::dds_::VehicleCommand_>> cmd;
        physics::Vec3 home;
    };
    void command(Vehicle& v, std::uint32_t command, float p1, float p2);
    std::deque<Vehicle> vehicles_;  // stable: topic names are referenced by the writers' specs
    std::deque<dds::Topic<px4_msgs::msg::dds_::TrajectorySetpoint_>> traj_specs_;
    std::deque<dds::Topic<px4_msgs::msg::dds_::OffboardControlMode_>> mode_specs_;
    std::deque<dds::Topic<px4_msgs::msg::dds_::VehicleCommand_>> cmd_specs_;
};

inline constexpr std::uint32_t kVehicleCmdDoSetMode = 176;
inline constexpr std::uint32_t kVehicleCmdArmDisarm = 400;
inline constexpr std::uint32_t kVehicleCmdNavLand = 21;

}  // namespace dw::planner
