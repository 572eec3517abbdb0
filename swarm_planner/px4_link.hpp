#pragma once
// The PX4 vehicle link, over PX4's uXRCE-DDS bridge on the lab's domain, for each vehicle
// (its namespace, MAV_SYS_ID, origin and heading from Px4Options):
// - setpoints: OffboardControlMode + TrajectorySetpoint on rt/<ns>/fmu/in/..., in its local NED,
//   stamped in microseconds of this host's realtime clock (the Agent's host must agree: OPERATOR.md);
// - the motion capture into its estimator: vehicle_visual_odometry from vehicles/state (NED,
//   w-first quaternion normalised, variances from the options) at the configured rate;
// - arming: DO_SET_MODE offboard, then ARM, each addressed to its own system id, confirmed by
//   vehicle_status (nav_state OFFBOARD, arming_state ARMED), retried, refused in one line with
//   PX4's answer (vehicle_command_ack) when there is one;
// - in flight: vehicle_status leaving OFFBOARD, disarming, a failsafe or silence is an abort reason;
// - landing: NAV_LAND; from an abort or a landing on, no setpoint above where PX4's own estimate
//   (fmu/out/vehicle_odometry) puts the vehicle (VehicleLink's descent);
// - what it sent, in the lab's frame, on vehicles/setpoint for the recording.
// The message layouts follow the configured PX4 version (dds/px4.hpp).
#include <memory>

#include "swarm_planner/vehicle_link.hpp"

namespace dw::planner {

std::unique_ptr<VehicleLink> make_px4_link(dds::Participant& p, const Px4Options& o, const std::string& run_id);

}  // namespace dw::planner
