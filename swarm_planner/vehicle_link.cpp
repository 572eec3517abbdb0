#include "swarm_planner/vehicle_link.hpp"

#include "dds/time.hpp"

namespace dw::planner {

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

Px4Link::Px4Link(dds::Participant& p, const std::vector<std::string>& vehicles, std::vector<physics::Vec3> home) {
    for (std::size_t i = 0; i < vehicles.size(); ++i) {
        Vehicle& v = vehicles_.emplace_back();
        const std::string base = "rt/" + vehicles[i] + "/fmu/in/";  // PX4_UXRCE_DDS_NS = the vehicle id
        v.traj_topic = base + "trajectory_setpoint";
        v.mode_topic = base + "offboard_control_mode";
        v.cmd_topic = base + "vehicle_command";
        v.home = i < home.size() ? home[i] : physics::Vec3::Zero();
        // PX4's subscribers are BEST_EFFORT, VOLATILE, KEEP_LAST: the sensor profile matches.
        traj_specs_.push_back({v.traj_topic, dds::QosProfile::sensor, "px4_msgs::msg::dds_::TrajectorySetpoint_", "", "Px4"});
        mode_specs_.push_back({v.mode_topic, dds::QosProfile::sensor, "px4_msgs::msg::dds_::OffboardControlMode_", "", "Px4"});
        cmd_specs_.push_back({v.cmd_topic, dds::QosProfile::sensor, "px4_msgs::msg::dds_::VehicleCommand_", "", "Px4"});
        v.traj = std::make_unique<dds::Writer<px4_msgs::msg::dds_::TrajectorySetpoint_>>(p, traj_specs_.back());
        v.mode = std::make_unique<dds::Writer<px4_msgs::msg::dds_::OffboardControlMode_>>(p, mode_specs_.back());
        v.cmd = std::make_unique<dds::Writer<px4_msgs::msg::dds_::VehicleCommand_>>(p, cmd_specs_.back());
    }
}

void Px4Link::send(const std::vector<physics::Setpoint>& sps, Nanos now_ns) {
    const auto us = static_cast<std::uint64_t>(now_ns / 1000);
    for (std::size_t i = 0; i < sps.size() && i < vehicles_.size(); ++i) {
        Vehicle& v = vehicles_[i];
        px4_msgs::msg::dds_::OffboardControlMode_ mode;  // proof of life, with every setpoint (>2 Hz)
        mode.timestamp(us);
        mode.position(true);
        mode.velocity(true);
        mode.acceleration(true);
        v.mode->write_as_is(mode);
        px4_msgs::msg::dds_::TrajectorySetpoint_ t;  // the lab's NED -> PX4's local NED: minus home
        t.timestamp(us);
        const physics::Vec3 local = sps[i].position - v.home;
        for (int k = 0; k < 3; ++k) {
            t.position()[static_cast<std::size_t>(k)] = static_cast<float>(local[k]);
            t.velocity()[static_cast<std::size_t>(k)] = static_cast<float>(sps[i].velocity[k]);
            t.acceleration()[static_cast<std::size_t>(k)] = static_cast<float>(sps[i].acceleration[k]);
            t.jerk()[static_cast<std::size_t>(k)] = std::numeric_limits<float>::quiet_NaN();
        }
        t.yaw(static_cast<float>(sps[i].yaw_rad));
        t.yawspeed(std::numeric_limits<float>::quiet_NaN());
        v.traj->write_as_is(t);
    }
}

void Px4Link::command(Vehicle& v, std::uint32_t command, float p1, float p2) {
    px4_msgs::msg::dds_::VehicleCommand_ c;
    c.command(command);
    c.param1(p1);
    c.param2(p2);
    c.target_system(1);
    c.target_component(1);
    c.source_system(1);
    c.source_component(1);
    c.from_external(true);
    v.cmd->write_as_is(c);
}

void Px4Link::start() {
    for (auto& v : vehicles_) {
        command(v, kVehicleCmdDoSetMode, 1.0f, 6.0f);  // custom mode: PX4_CUSTOM_MAIN_MODE_OFFBOARD
        command(v, kVehicleCmdArmDisarm, 1.0f, 0.0f);
    }
}

void Px4Link::land() {
    for (auto& v : vehicles_) command(v, kVehicleCmdNavLand, 0.0f, 0.0f);
}

}  // namespace dw::planner
