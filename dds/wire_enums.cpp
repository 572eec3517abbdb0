#include "dds/wire_enums.hpp"

#include <algorithm>
#include <cctype>

#include "core/names.hpp"

namespace dw::dds {

const char* phase_name(msg::ExperimentPhase p) {
    switch (p) {
        case msg::PHASE_IDLE: return "IDLE";
        case msg::PHASE_WAITING: return "WAITING";
        case msg::PHASE_CALIBRATING: return "CALIBRATING";
        case msg::PHASE_TAKING_OFF: return "TAKING_OFF";
        case msg::PHASE_FLYING: return "FLYING";
        case msg::PHASE_LANDING: return "LANDING";
        case msg::PHASE_DONE: return "DONE";
        case msg::PHASE_ABORTED: return "ABORTED";
    }
    return "?";
}

const char* command_name(msg::CommandKind k) {
    switch (k) {
        case msg::CMD_START: return "START";
        case msg::CMD_CALIBRATE: return "CALIBRATE";
        case msg::CMD_PAUSE: return "PAUSE";
        case msg::CMD_RESUME: return "RESUME";
        case msg::CMD_ABORT: return "ABORT";
        case msg::CMD_STOP: return "STOP";
    }
    return "?";
}

namespace {
std::string lower(std::string_view s) {
    std::string out(s);
    for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return out;
}
}  // namespace

std::vector<std::string> command_names() {
    std::vector<std::string> out;
    // CMD_START .. CMD_STOP: the IDL's first and last enumerators.
    for (int k = static_cast<int>(msg::CMD_START); k <= static_cast<int>(msg::CMD_STOP); ++k)
        out.push_back(lower(command_name(static_cast<msg::CommandKind>(k))));
    return out;
}

std::optional<msg::CommandKind> command_named(std::string_view name) {
    const auto i = find_name(command_names(), lower(name));
    if (!i) return std::nullopt;
    return static_cast<msg::CommandKind>(static_cast<int>(msg::CMD_START) + static_cast<int>(*i));
}

const char* process_state_name(msg::ProcessState s) {
    switch (s) {
        case msg::PROC_STARTING: return "STARTING";
        case msg::PROC_RUNNING: return "RUNNING";
        case msg::PROC_DEGRADED: return "DEGRADED";
        case msg::PROC_FAULT: return "FAULT";
        case msg::PROC_STOPPING: return "STOPPING";
    }
    return "?";
}

const char* stand_state_name(msg::StandState s) {
    switch (s) {
        case msg::STAND_STARTING: return "STARTING";
        case msg::STAND_TARING: return "TARING";
        case msg::STAND_RUNNING: return "RUNNING";
        case msg::STAND_FAULT: return "FAULT";
    }
    return "?";
}

}  // namespace dw::dds
