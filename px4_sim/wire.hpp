#pragma once
// PX4's messages as PX4 itself lays them out, written from px4_msgs' .msg definitions (tags
// v1.14.0, v1.15.4, v1.16.2; ../shared/SPECS.md §3), independent of the lab's IDL: PX4's ucdr
// code writes the fields in .msg order, each at its natural alignment (counted from the start of
// the CDR body, at most 8), fixed arrays without a length, constants not at all; the DDS payload
// starts with the 4-byte CDR encapsulation (00 01 00 00: little endian). The simulated PX4 reads
// and writes its topics with these, and the tests decode what the lab's PX4 link sends with them.
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "dds/px4.hpp"

namespace dw::px4sim {

enum class Kind : std::uint8_t { u8, i8, boolean, u16, i32, u32, u64, f32, f64 };
struct Field {
    std::string_view name;
    Kind kind;
    std::uint8_t count = 1;  // > 1: a fixed array
};
struct MsgDef {
    std::string_view type;  // the .msg name: VehicleCommand
    std::vector<Field> fields;
};

enum class Msg {
    trajectory_setpoint,
    offboard_control_mode,
    vehicle_command,
    vehicle_odometry,
    vehicle_status,
    vehicle_command_ack
};
// The definition of that message in that PX4 version.
const MsgDef& msg_def(Msg msg, dds::Px4Version version);
// Bytes of the CDR body (without the encapsulation).
std::size_t body_size(const MsgDef& def);

// Field values by name (arrays: one value per element). A field not given is 0.
using Values = std::map<std::string, std::vector<double>, std::less<>>;
std::vector<std::uint8_t> encode(const MsgDef& def, const Values& values);
// Throws dw::InputError when the payload is shorter than the definition or not little-endian CDR.
Values decode(const MsgDef& def, std::span<const std::uint8_t> payload);
// The one value of a scalar field.
double value(const Values& v, std::string_view field);

}  // namespace dw::px4sim
