#pragma once
// PX4's uXRCE-DDS types (idl/Px4.idl) for the lab's typed writers and readers.
#include "dds/topics.hpp"
#include "dw/msg/Px4PubSubTypes.h"

namespace dw::dds {

#define DW_PX4_PUBSUB(T) template <> struct PubSubOf<px4_msgs::msg::dds_::T##_> { using type = px4_msgs::msg::dds_::T##_PubSubType; }
DW_PX4_PUBSUB(TrajectorySetpoint);
DW_PX4_PUBSUB(OffboardControlMode);
DW_PX4_PUBSUB(VehicleCommand);
DW_PX4_PUBSUB(VehicleOdometry);
#undef DW_PX4_PUBSUB

}  // namespace dw::dds
