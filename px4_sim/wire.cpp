#include "px4_sim/wire.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::px4sim {
namespace {

using K = Kind;
using V = dds::Px4Version;

std::size_t size_of(Kind k) {
    switch (k) {
        case K::u8:
        case K::i8:
        case K::boolean: return 1;
        case K::u16: return 2;
        case K::i32:
        case K::u32:
        case K::f32: return 4;
        case K::u64:
        case K::f64: return 8;
    }
    return 1;
}

// msg/TrajectorySetpoint.msg (unchanged 1.14-1.16)
const MsgDef kTrajectorySetpoint{"TrajectorySetpoint",
                                 {{"timestamp", K::u64},
                                  {"position", K::f32, 3},
                                  {"velocity", K::f32, 3},
                                  {"acceleration", K::f32, 3},
                                  {"jerk", K::f32, 3},
                                  {"yaw", K::f32},
                                  {"yawspeed", K::f32}}};
// msg/OffboardControlMode.msg: v1.14 ends with `actuator`; v1.15 renamed it and added a flag.
const MsgDef kOffboardControlMode114{"OffboardControlMode",
                                     {{"timestamp", K::u64},
                                      {"position", K::boolean},
                                      {"velocity", K::boolean},
                                      {"acceleration", K::boolean},
                                      {"attitude", K::boolean},
                                      {"body_rate", K::boolean},
                                      {"actuator", K::boolean}}};
const MsgDef kOffboardControlMode115{"OffboardControlMode",
                                     {{"timestamp", K::u64},
                                      {"position", K::boolean},
                                      {"velocity", K::boolean},
                                      {"acceleration", K::boolean},
                                      {"attitude", K::boolean},
                                      {"body_rate", K::boolean},
                                      {"thrust_and_torque", K::boolean},
                                      {"direct_actuator", K::boolean}}};
// msg/VehicleCommand.msg: source_component uint8 in v1.14, uint16 from v1.15 (mode executors).
std::vector<Field> vehicle_command(Kind source_component) {
    return {{"timestamp", K::u64},
            {"param1", K::f32},
            {"param2", K::f32},
            {"param3", K::f32},
            {"param4", K::f32},
            {"param5", K::f64},
            {"param6", K::f64},
            {"param7", K::f32},
            {"command", K::u32},
            {"target_system", K::u8},
            {"target_component", K::u8},
            {"source_system", K::u8},
            {"source_component", source_component},
            {"confirmation", K::u8},
            {"from_external", K::boolean}};
}
const MsgDef kVehicleCommand114{"VehicleCommand", vehicle_command(K::u8)};
const MsgDef kVehicleCommand115{"VehicleCommand", vehicle_command(K::u16)};
// msg/VehicleOdometry.msg (unchanged 1.14-1.16)
const MsgDef kVehicleOdometry{"VehicleOdometry",
                              {{"timestamp", K::u64},
                               {"timestamp_sample", K::u64},
                               {"pose_frame", K::u8},
                               {"position", K::f32, 3},
                               {"q", K::f32, 4},
                               {"velocity_frame", K::u8},
                               {"velocity", K::f32, 3},
                               {"angular_velocity", K::f32, 3},
                               {"position_variance", K::f32, 3},
                               {"orientation_variance", K::f32, 3},
                               {"velocity_variance", K::f32, 3},
                               {"reset_counter", K::u8},
                               {"quality", K::i8}}};
// msg/VehicleCommandAck.msg: target_component uint16 from v1.15 (uint8 before: unverified for 1.14).
std::vector<Field> vehicle_command_ack(Kind target_component) {
    return {{"timestamp", K::u64},
            {"command", K::u32},
            {"result", K::u8},
            {"result_param1", K::u8},
            {"result_param2", K::i32},
            {"target_system", K::u8},
            {"target_component", target_component},
            {"from_external", K::boolean}};
}
const MsgDef kVehicleCommandAck114{"VehicleCommandAck", vehicle_command_ack(K::u8)};
const MsgDef kVehicleCommandAck115{"VehicleCommandAck", vehicle_command_ack(K::u16)};

// msg/VehicleStatus.msg, the whole message: v1.15 added executor_in_charge, the nav-state masks
// and failsafe_defer_state; v1.16 removed the avoidance flags (and versioned the topic).
std::vector<Field> vehicle_status(V v) {
    std::vector<Field> f{{"timestamp", K::u64},
                         {"armed_time", K::u64},
                         {"takeoff_time", K::u64},
                         {"arming_state", K::u8},
                         {"latest_arming_reason", K::u8},
                         {"latest_disarming_reason", K::u8},
                         {"nav_state_timestamp", K::u64},
                         {"nav_state_user_intention", K::u8},
                         {"nav_state", K::u8}};
    if (v != V::v1_14)
        f.insert(
            f.end(),
            {{"executor_in_charge", K::u8}, {"valid_nav_states_mask", K::u32}, {"can_set_nav_states_mask", K::u32}});
    f.insert(f.end(), {{"failure_detector_status", K::u16},
                       {"hil_state", K::u8},
                       {"vehicle_type", K::u8},
                       {"failsafe", K::boolean},
                       {"failsafe_and_user_took_over", K::boolean}});
    if (v != V::v1_14) f.push_back({"failsafe_defer_state", K::u8});
    f.insert(f.end(), {{"gcs_connection_lost", K::boolean},
                       {"gcs_connection_lost_counter", K::u8},
                       {"high_latency_data_link_lost", K::boolean},
                       {"is_vtol", K::boolean},
                       {"is_vtol_tailsitter", K::boolean},
                       {"in_transition_mode", K::boolean},
                       {"in_transition_to_fw", K::boolean},
                       {"system_type", K::u8},
                       {"system_id", K::u8},
                       {"component_id", K::u8},
                       {"safety_button_available", K::boolean},
                       {"safety_off", K::boolean},
                       {"power_input_valid", K::boolean},
                       {"usb_connected", K::boolean},
                       {"open_drone_id_system_present", K::boolean},
                       {"open_drone_id_system_healthy", K::boolean},
                       {"parachute_system_present", K::boolean},
                       {"parachute_system_healthy", K::boolean}});
    if (v != V::v1_16)
        f.insert(f.end(), {{"avoidance_system_required", K::boolean}, {"avoidance_system_valid", K::boolean}});
    f.insert(f.end(), {{"rc_calibration_in_progress", K::boolean},
                       {"calibration_enabled", K::boolean},
                       {"pre_flight_checks_pass", K::boolean}});
    return f;
}
const MsgDef kVehicleStatus114{"VehicleStatus", vehicle_status(V::v1_14)};
const MsgDef kVehicleStatus115{"VehicleStatus", vehicle_status(V::v1_15)};
const MsgDef kVehicleStatus116{"VehicleStatus", vehicle_status(V::v1_16)};

std::size_t align(std::size_t at, Kind k) {
    const std::size_t a = size_of(k);
    return (at + a - 1) / a * a;
}

template <class T>
void put(std::vector<std::uint8_t>& out, std::size_t at, double v) {
    T x{};
    if constexpr (std::is_floating_point_v<T>) {
        x = static_cast<T>(v);
    } else if (std::isfinite(v)) {  // integers: clamped to the type (a cast out of range is undefined)
        double hi = static_cast<double>(std::numeric_limits<T>::max());
        if constexpr (sizeof(T) == 8) hi = std::nextafter(hi, 0.0);  // 2^64 - 1 rounds up to 2^64 in a double
        x = static_cast<T>(std::clamp(v, static_cast<double>(std::numeric_limits<T>::lowest()), hi));
    }
    std::memcpy(out.data() + at, &x, sizeof x);
}
template <class T>
double get(std::span<const std::uint8_t> in, std::size_t at) {
    T x;
    std::memcpy(&x, in.data() + at, sizeof x);
    return static_cast<double>(x);
}

void put_value(std::vector<std::uint8_t>& out, std::size_t at, Kind k, double v) {
    switch (k) {
        case K::u8:
        case K::boolean: return put<std::uint8_t>(out, at, v);
        case K::i8: return put<std::int8_t>(out, at, v);
        case K::u16: return put<std::uint16_t>(out, at, v);
        case K::i32: return put<std::int32_t>(out, at, v);
        case K::u32: return put<std::uint32_t>(out, at, v);
        case K::u64: return put<std::uint64_t>(out, at, v);
        case K::f32: return put<float>(out, at, v);
        case K::f64: return put<double>(out, at, v);
    }
}
double get_value(std::span<const std::uint8_t> in, std::size_t at, Kind k) {
    switch (k) {
        case K::u8:
        case K::boolean: return get<std::uint8_t>(in, at);
        case K::i8: return get<std::int8_t>(in, at);
        case K::u16: return get<std::uint16_t>(in, at);
        case K::i32: return get<std::int32_t>(in, at);
        case K::u32: return get<std::uint32_t>(in, at);
        case K::u64: return get<std::uint64_t>(in, at);
        case K::f32: return get<float>(in, at);
        case K::f64: return get<double>(in, at);
    }
    return 0;
}

constexpr std::size_t kEncapsulation = 4;
constexpr std::uint8_t kCdrLe = 0x01;

}  // namespace

const MsgDef& msg_def(Msg msg, dds::Px4Version v) {
    const bool v114 = v == V::v1_14;
    switch (msg) {
        case Msg::trajectory_setpoint: return kTrajectorySetpoint;
        case Msg::offboard_control_mode: return v114 ? kOffboardControlMode114 : kOffboardControlMode115;
        case Msg::vehicle_command: return v114 ? kVehicleCommand114 : kVehicleCommand115;
        case Msg::vehicle_odometry: return kVehicleOdometry;
        case Msg::vehicle_command_ack: return v114 ? kVehicleCommandAck114 : kVehicleCommandAck115;
        case Msg::vehicle_status:
            return v114 ? kVehicleStatus114 : v == V::v1_15 ? kVehicleStatus115 : kVehicleStatus116;
    }
    throw RuntimeError("unknown PX4 message");
}

std::size_t body_size(const MsgDef& def) {
    std::size_t at = 0;
    for (const auto& f : def.fields) at = align(at, f.kind) + size_of(f.kind) * f.count;
    return at;
}

std::vector<std::uint8_t> encode(const MsgDef& def, const Values& values) {
    std::vector<std::uint8_t> out(kEncapsulation + body_size(def), 0);
    out[1] = kCdrLe;
    std::size_t at = 0;  // in the body: alignment counts from there
    for (const auto& f : def.fields) {
        at = align(at, f.kind);
        const auto it = values.find(f.name);
        for (std::size_t i = 0; i < f.count; ++i, at += size_of(f.kind)) {
            const double v = it != values.end() && i < it->second.size() ? it->second[i] : 0.0;
            put_value(out, kEncapsulation + at, f.kind, v);
        }
    }
    return out;
}

Values decode(const MsgDef& def, std::span<const std::uint8_t> payload) {
    if (payload.size() < kEncapsulation || payload[0] != 0 || payload[1] != kCdrLe)
        throw InputError(log::cat(def.type, ": not a little-endian CDR payload"));
    const auto body = payload.subspan(kEncapsulation);
    if (body.size() < body_size(def))
        throw InputError(log::cat(def.type, ": ", body.size(), " bytes, the definition needs ", body_size(def)));
    Values out;
    std::size_t at = 0;
    for (const auto& f : def.fields) {
        at = align(at, f.kind);
        auto& v = out[std::string(f.name)];
        for (std::size_t i = 0; i < f.count; ++i, at += size_of(f.kind)) v.push_back(get_value(body, at, f.kind));
    }
    return out;
}

double value(const Values& v, std::string_view field) {
    const auto it = v.find(field);
    if (it == v.end() || it->second.empty()) throw InputError("no field " + std::string(field));
    return it->second.front();
}

}  // namespace dw::px4sim
