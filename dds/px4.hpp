#pragma once
// PX4's uXRCE-DDS types (idl/Px4.idl, idl/Px4v114.idl, idl/Px4v116.idl) for the lab's typed writers and readers,
// the PX4 versions the lab supports, and PX4's own numbers (commands, states, results), each
// defined once here. Sources: ../shared/SPECS.md §3, docs/research/PX4_LINK.md.
#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <ranges>
#include <string>
#include <string_view>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "dds/topics.hpp"
#include "dw/msg/Px4PubSubTypes.h"
#include "dw/msg/Px4v114PubSubTypes.h"
#include "dw/msg/Px4v116PubSubTypes.h"

namespace dw::dds {

#define DW_PX4_PUBSUB(T)                                  \
    template <>                                           \
    struct PubSubOf<px4_msgs::msg::dds_::T##_> {          \
        using type = px4_msgs::msg::dds_::T##_PubSubType; \
    }
DW_PX4_PUBSUB(TrajectorySetpoint);
DW_PX4_PUBSUB(OffboardControlMode);
DW_PX4_PUBSUB(VehicleCommand);
DW_PX4_PUBSUB(VehicleOdometry);
DW_PX4_PUBSUB(VehicleStatus);
DW_PX4_PUBSUB(VehicleCommandAck);
#undef DW_PX4_PUBSUB

// PX4 v1.14's types go on the wire under PX4's one type name per message.
#define DW_PX4_V114_PUBSUB(T)                                             \
    struct T##V114PubSubType : px4_msgs_v114::msg::dds_::T##_PubSubType { \
        T##V114PubSubType() { setName("px4_msgs::msg::dds_::" #T "_"); }  \
    };                                                                    \
    template <>                                                           \
    struct PubSubOf<px4_msgs_v114::msg::dds_::T##_> {                     \
        using type = T##V114PubSubType;                                   \
    }
DW_PX4_V114_PUBSUB(OffboardControlMode);
DW_PX4_V114_PUBSUB(VehicleCommand);
DW_PX4_V114_PUBSUB(VehicleStatus);
DW_PX4_V114_PUBSUB(VehicleCommandAck);
#undef DW_PX4_V114_PUBSUB

// PX4 v1.16's vehicle_status_v1, under PX4's one type name.
struct VehicleStatusV116PubSubType : px4_msgs_v116::msg::dds_::VehicleStatus_PubSubType {
    VehicleStatusV116PubSubType() { setName("px4_msgs::msg::dds_::VehicleStatus_"); }
};
template <>
struct PubSubOf<px4_msgs_v116::msg::dds_::VehicleStatus_> {
    using type = VehicleStatusV116PubSubType;
};

// The PX4 releases the lab speaks to, and what differs between them on the wire.
enum class Px4Version { v1_14, v1_15, v1_16 };
struct Px4VersionInfo {
    Px4Version version;
    std::string_view name;          // as written in the planner's PX4 file: "1.15"
    std::string_view status_topic;  // fmu/out/<this>: v1.16 versions VehicleStatus (MESSAGE_VERSION 1)
    std::string_view ack_topic;     // unversioned through v1.16 (MESSAGE_VERSION 0; _v1 only on later main)
    // Whether PX4's own dds_topics.yaml bridges vehicle_command_ack: v1.14's does not (an answer,
    // a refusal's reason included, never leaves the vehicle unless the lab adds it there).
    bool ack_bridged;
};
inline constexpr std::array<Px4VersionInfo, 3> kPx4Versions{{
    {Px4Version::v1_14, "1.14", "vehicle_status", "vehicle_command_ack", false},
    {Px4Version::v1_15, "1.15", "vehicle_status", "vehicle_command_ack", true},
    {Px4Version::v1_16, "1.16", "vehicle_status_v1", "vehicle_command_ack", true},
}};
inline const Px4VersionInfo& px4_version(Px4Version v) {
    for (const auto& i : kPx4Versions)
        if (i.version == v) return i;
    throw RuntimeError("unknown PX4 version");
}
// The versions' names in kPx4Versions' order.
inline auto px4_version_names() {
    return std::views::transform(kPx4Versions, [](const Px4VersionInfo& i) { return i.name; });
}
// "1.15" -> Px4Version::v1_15, or nullopt.
inline std::optional<Px4Version> find_px4_version(std::string_view text) {
    const auto i = find_name(px4_version_names(), text);
    return i ? std::optional(kPx4Versions[*i].version) : std::nullopt;
}
// The one message for a version the lab does not speak to.
inline std::string unknown_px4_version_problem(std::string_view text) {
    return unknown_name_problem("PX4 version", text, px4_version_names(), "; other releases are not supported");
}

// rt/[<ns>/]fmu/<in|out>/<name>: PX4's uXRCE-DDS client names (its start line's -n gives ns).
inline std::string px4_topic(std::string_view ns, std::string_view direction, std::string_view name) {
    return "rt/" + (ns.empty() ? std::string() : std::string(ns) + "/") + "fmu/" + std::string(direction) + "/" +
           std::string(name);
}

// A PX4 topic's spec for the lab's typed endpoints: PX4's QoS, PX4's type name. The spec views
// `name`, which must outlive it.
template <class T>
Topic<T> px4_topic_spec(const std::string& name, std::string_view type) {
    return {name, QosProfile::px4, type, "PX4 uXRCE-DDS", "Px4"};
}

namespace px4 {
// A field PX4 must ignore (a setpoint's unused terms, an odometry's unmeasured ones): NaN.
inline constexpr float kUnset = std::numeric_limits<float>::quiet_NaN();
// VehicleCommand.command (MAVLink MAV_CMD), as PX4's Commander handles them.
inline constexpr std::uint32_t kCmdNavLand = 21;
inline constexpr std::uint32_t kCmdDoSetMode = 176;
inline constexpr std::uint32_t kCmdArmDisarm = 400;
inline constexpr std::array<std::pair<std::uint32_t, std::string_view>, 3> kCommandNames{{
    {kCmdNavLand, "NAV_LAND"},
    {kCmdDoSetMode, "DO_SET_MODE"},
    {kCmdArmDisarm, "COMPONENT_ARM_DISARM"},
}};
// A command's MAV_CMD name, or "MAV_CMD <n>" for one the lab does not send.
inline std::string command_name(std::uint32_t c) {
    for (const auto& [v, n] : kCommandNames)
        if (v == c) return std::string(n);
    return "MAV_CMD " + std::to_string(c);
}
inline constexpr float kModeFlagCustom = 1.0f;          // DO_SET_MODE param1: custom main mode in param2
inline constexpr float kCustomMainModeOffboard = 6.0f;  // PX4_CUSTOM_MAIN_MODE_OFFBOARD
// Commander answers commands for its own MAV_SYS_ID / MAV_COMP_ID, or for 0 ("every").
inline constexpr std::uint8_t kAutopilotComponent = 1;
// The planner's own MAVLink identity (a ground station's: system 255, component 190).
inline constexpr std::uint8_t kPlannerSystem = 255;
inline constexpr std::uint8_t kPlannerComponent = 190;

// VehicleOdometry (every version): pose_frame / velocity_frame, and its best quality.
inline constexpr std::uint8_t kFrameNed = 1;
inline constexpr std::uint8_t kFrameFrd = 2;
inline constexpr std::int8_t kQualityBest = 100;

inline constexpr std::uint8_t kArmed = 2;  // arming_state, every version
inline constexpr std::uint8_t kNavOffboard = 14;
inline constexpr std::uint8_t kNavAutoLand = 18;
inline constexpr std::uint8_t kNavDescend = 12;  // a landing without a position: PX4's "blind land"
inline constexpr std::uint8_t kNavTermination = 13;

inline constexpr std::array<std::pair<std::uint8_t, std::string_view>, 17> kNavStateNames{{
    {0, "MANUAL"},
    {1, "ALTCTL"},
    {2, "POSCTL"},
    {3, "AUTO_MISSION"},
    {4, "AUTO_LOITER"},
    {5, "AUTO_RTL"},
    {6, "POSITION_SLOW"},
    {10, "ACRO"},
    {12, "DESCEND"},
    {13, "TERMINATION"},
    {14, "OFFBOARD"},
    {15, "STAB"},
    {17, "AUTO_TAKEOFF"},
    {18, "AUTO_LAND"},
    {19, "AUTO_FOLLOW_TARGET"},
    {20, "AUTO_PRECLAND"},
    {21, "ORBIT"},
}};
// A value's name in one of PX4's enum tables, or "<field> <value>" for one the table lacks.
template <std::size_t N>
std::string enum_name(const std::array<std::pair<std::uint8_t, std::string_view>, N>& table, std::uint8_t value,
                      std::string_view field) {
    for (const auto& [v, n] : table)
        if (v == value) return std::string(n);
    return std::string(field) + " " + std::to_string(value);
}
inline std::string nav_state_name(std::uint8_t s) { return enum_name(kNavStateNames, s, "nav_state"); }

// VehicleStatus.latest_disarming_reason (ARM_DISARM_REASON_*, the same values in 1.14-1.16).
inline constexpr std::uint8_t kDisarmAfterLanding = 7;
inline constexpr std::uint8_t kDisarmKillSwitch = 9;
inline constexpr std::array<std::pair<std::uint8_t, std::string_view>, 14> kDisarmReasonNames{{
    {0, "transition to standby"},
    {1, "stick gesture"},
    {2, "RC switch"},
    {3, "an internal command"},
    {4, "an external command"},
    {5, "mission start"},
    {6, "safety button"},
    {kDisarmAfterLanding, "auto-disarm after landing"},
    {8, "auto-disarm before take-off"},
    {kDisarmKillSwitch, "kill switch"},
    {10, "lockdown"},
    {11, "failure detector"},
    {12, "shutdown"},
    {13, "unit test"},
}};
inline std::string disarm_reason_name(std::uint8_t r) { return enum_name(kDisarmReasonNames, r, "disarm reason"); }

// VehicleCommandAck.result
enum class AckResult : std::uint8_t {
    accepted = 0,
    temporarily_rejected = 1,
    denied = 2,
    unsupported = 3,
    failed = 4,
    in_progress = 5,
    cancelled = 6
};
inline constexpr std::array<std::string_view, 7> kAckResultNames{
    "ACCEPTED", "TEMPORARILY_REJECTED", "DENIED", "UNSUPPORTED", "FAILED", "IN_PROGRESS", "CANCELLED"};
inline std::string ack_result_name(std::uint8_t r) {
    return r < kAckResultNames.size() ? std::string(kAckResultNames[r]) : "result " + std::to_string(r);
}
}  // namespace px4

}  // namespace dw::dds
