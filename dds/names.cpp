#include "dds/names.hpp"

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
