#pragma once
// Every lab topic, its type and its QoS profile, in one place. Names follow the ROS 2 convention
// rt/<namespace>/<suffix> (namespace "lab" by default), so ROS 2 tools on the same domain list
// them. Add a topic here and every tool that visits all topics (dw-probe, the recorder) gets it.
#include <string>
#include <string_view>
#include <vector>

#include "dds/qos.hpp"
#include "dds/roles.hpp"
#include "dw/msg/ExperimentPubSubTypes.h"
#include "dw/msg/MocapPubSubTypes.h"
#include "dw/msg/PredictionPubSubTypes.h"
#include "dw/msg/StandPubSubTypes.h"
#include "dw/msg/StatusPubSubTypes.h"
#include "dw/msg/VehiclePubSubTypes.h"
#include "dw/msg/WrenchPubSubTypes.h"

namespace dw::dds {

// The Fast DDS type support of a message type.
template <class T>
struct PubSubOf;
#define DW_PUBSUB(T)                     \
    template <>                          \
    struct PubSubOf<msg::T> {            \
        using type = msg::T##PubSubType; \
    }
DW_PUBSUB(WrenchStamped);
DW_PUBSUB(LoadCellFrame);
DW_PUBSUB(StandStatus);
DW_PUBSUB(MocapFrame);
DW_PUBSUB(VehicleState);
DW_PUBSUB(VehicleSetpoint);
DW_PUBSUB(VehicleCommandSent);
DW_PUBSUB(ExperimentPlan);
DW_PUBSUB(ExperimentCommand);
DW_PUBSUB(ExperimentState);
DW_PUBSUB(WrenchPrediction);
DW_PUBSUB(ProcessStatus);
DW_PUBSUB(ClockProbe);
#undef DW_PUBSUB

// What DDS Security does to a topic's samples on the wire: signed (anyone on the wire may read,
// no one may forge) or encrypted (and no one may read).
enum class Protection { sign, encrypt };

template <class T>
struct Topic {
    using type = T;
    std::string_view suffix;  // after rt/<namespace>/
    QosProfile qos;
    std::string_view type_name;  // the scoped IDL name, as registered with DDS
    std::string_view description;
    std::string_view idl;                      // the IDL file defining the type (idl/<idl>.idl)
    Roles producers = 0;                       // who publishes it (DDS Security permissions follow from these)
    Roles consumers = 0;                       // who subscribes to it
    Protection protection = Protection::sign;  // on the wire, under DDS Security (dw-lab keys' governance)
    std::string_view protection_reason = {};   // why: what leaking or forging it would cost
    // It moves vehicles or starts and stops work: no writer publishes a non-finite number on it,
    // and `dw-recorder replay` leaves it out unless asked (--commands).
    bool command = false;
};

namespace topics {
using namespace dw::msg;
inline constexpr Topic<WrenchStamped> stand_wrench{
    "stand/wrench",
    QosProfile::sensor,
    "dw::msg::WrenchStamped",
    "calibrated 6-DOF wrench on the sufferer (80 Hz)",
    "Wrench",
    Roles(Role::stand_agent),
    Role::recorder | Role::operator_ | Role::viewer,
    Protection::sign,
    "the measurement itself: forged, it corrupts the study; read, it costs nothing"};
inline constexpr Topic<LoadCellFrame> stand_cells{"stand/cells",
                                                  QosProfile::sensor,
                                                  "dw::msg::LoadCellFrame",
                                                  "raw counts of the 8 load cells (80 Hz)",
                                                  "Stand",
                                                  Roles(Role::stand_agent),
                                                  Role::recorder | Role::operator_ | Role::viewer,
                                                  Protection::sign,
                                                  "raw counts behind the wrench: the same as stand/wrench"};
inline constexpr Topic<StandStatus> stand_status{
    "stand/status",
    QosProfile::state,
    "dw::msg::StandStatus",
    "stand agent state, faults and tare (latched)",
    "Stand",
    Roles(Role::stand_agent),
    Role::recorder | Role::launcher | Role::operator_ | Role::viewer,
    Protection::sign,
    "a forged READY or tare would start an experiment on an untared stand"};
inline constexpr Topic<MocapFrame> mocap_frame{
    "mocap/frame",
    QosProfile::sensor,
    "dw::msg::MocapFrame",
    "one motion-capture frame, every rigid body (180 Hz)",
    "Mocap",
    Roles(Role::mocap_bridge),
    Role::stand_agent | Role::predictor | Role::recorder | Role::operator_ | Role::viewer,
    Protection::sign,
    "forged poses would mislead the predictor and the stand simulation; positions in a lab are no secret"};
inline constexpr Topic<VehicleState> vehicle_state{
    "vehicles/state",
    QosProfile::sensor,
    "dw::msg::VehicleState",
    "per-vehicle pose and velocity (keyed by vehicle_id)",
    "Vehicle",
    Roles(Role::mocap_bridge),
    Role::planner | Role::recorder | Role::operator_ | Role::viewer,
    Protection::sign,
    "the planner supervises tracking and the geofence on it: forged, it hides a vehicle going astray"};
inline constexpr Topic<VehicleSetpoint> vehicle_setpoint{
    "vehicles/setpoint",
    QosProfile::sensor,
    "dw::msg::VehicleSetpoint",
    "per-vehicle trajectory setpoint (keyed by vehicle_id, >= 50 Hz)",
    "Vehicle",
    Roles(Role::planner),
    Role::mocap_bridge | Role::recorder | Role::operator_ | Role::viewer,
    Protection::encrypt,
    "moves real multirotors over a person-sized stand: no one outside the lab may read or write it",
    true};
inline constexpr Topic<VehicleCommandSent> vehicle_command{
    "vehicles/command",
    QosProfile::command,
    "dw::msg::VehicleCommandSent",
    "every command the lab sent to a vehicle's autopilot: mode, arm, land (keyed by vehicle_id)",
    "Vehicle",
    Roles(Role::planner),
    Role::recorder | Role::operator_ | Role::viewer,
    Protection::encrypt,
    "what the lab asked of its vehicles, and when: no one outside the lab may read or forge it",
    true};
inline constexpr Topic<ExperimentPlan> experiment_plan{
    "experiment/plan",
    QosProfile::state,
    "dw::msg::ExperimentPlan",
    "the experiment's formation and legs (latched)",
    "Experiment",
    Roles(Role::planner),
    Role::recorder | Role::launcher | Role::operator_ | Role::viewer,
    Protection::encrypt,
    "the legs the vehicles will fly: kept from anyone outside the lab"};
inline constexpr Topic<ExperimentCommand> experiment_command{
    "experiment/command",
    QosProfile::command,
    "dw::msg::ExperimentCommand",
    "operator/planner commands: start, calibrate, pause, abort",
    "Experiment",
    Role::planner | Role::operator_,
    Role::stand_agent | Role::planner | Role::recorder | Role::viewer,
    Protection::encrypt,
    "start, abort and calibrate: only the planner and the operator, unseen",
    true};
inline constexpr Topic<ExperimentState> experiment_state{
    "experiment/state",
    QosProfile::state,
    "dw::msg::ExperimentState",
    "experiment phase, leg and progress (latched)",
    "Experiment",
    Roles(Role::planner),
    Role::launcher | Role::recorder | Role::operator_ | Role::viewer,
    Protection::sign,
    "a forged DONE or ABORTED would mislead the operator and the launcher"};
inline constexpr Topic<WrenchPrediction> wrench_prediction{"predictor/wrench",
                                                           QosProfile::sensor,
                                                           "dw::msg::WrenchPrediction",
                                                           "predicted wrench on the sufferer, per model",
                                                           "Prediction",
                                                           Roles(Role::predictor),
                                                           Role::recorder | Role::operator_ | Role::viewer,
                                                           Protection::sign,
                                                           "forged predictions would be recorded as the model's"};
inline constexpr Topic<ProcessStatus> process_status{
    "processes/status",
    QosProfile::heartbeat,
    "dw::msg::ProcessStatus",
    "heartbeat and status of every lab process (keyed by process)",
    "Status",
    kEveryPublisher,
    kEveryRole,
    Protection::sign,
    "forged heartbeats would hide a dead process from the supervision"};
inline constexpr Topic<ClockProbe> clock_request{
    "clock/request",
    QosProfile::command,
    "dw::msg::ClockProbe",
    "a process asks the reference clock (the recorder) for its time (every 0.5 s)",
    "Status",
    kEveryPublisher,
    Role::recorder | Role::viewer,
    Protection::sign,
    "forged requests only cost the recorder an answer"};
inline constexpr Topic<ClockProbe> clock_reply{
    "clock/reply",
    QosProfile::command,
    "dw::msg::ClockProbe",
    "the reference clock's answer: its time at receipt and at reply",
    "Status",
    Roles(Role::recorder),
    kEveryRole,
    Protection::sign,
    "forged answers would skew every process's measured clock offset, and the export's correction"};

// Calls f(topic) for every lab topic, in a fixed order.
template <class F>
constexpr void for_each(F&& f) {
    f(stand_wrench);
    f(stand_cells);
    f(stand_status);
    f(mocap_frame);
    f(vehicle_state);
    f(vehicle_setpoint);
    f(vehicle_command);
    f(experiment_plan);
    f(experiment_command);
    f(experiment_state);
    f(wrench_prediction);
    f(process_status);
    f(clock_request);
    f(clock_reply);
}
// How many: counted from the list above, never kept by hand.
inline constexpr int kTopicCount = [] {
    int n = 0;
    for_each([&](const auto&) { ++n; });
    return n;
}();
}  // namespace topics

// Topic suffixes ("stand/wrench") of every lab topic, in registry order.
std::vector<std::string> all_topics();
// Accepts suffixes, full names (rt/<ns>/...) or "all"; none = all. Throws dw::InputError for an
// unknown topic.
std::vector<std::string> select_topics(const std::vector<std::string>& requested, const std::string& ns);

}  // namespace dw::dds
