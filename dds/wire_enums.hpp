#pragma once
// The wire enums' names (IDL enumerators without their prefix), defined once for logs, status
// lines, the planner's state messages and dw-probe. Each is a switch over every enumerator, so a
// new one in the IDL is a compiler warning here, not a "?" somewhere else.
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "dw/msg/Experiment.h"
#include "dw/msg/Stand.h"
#include "dw/msg/Status.h"

namespace dw::dds {

const char* phase_name(msg::ExperimentPhase p);
const char* command_name(msg::CommandKind k);
// The command kind with this name, any case ("abort"); nullopt for none.
std::optional<msg::CommandKind> command_named(std::string_view name);
// Every command kind's name in lower case, in the IDL's order ("start" ... "stop").
std::vector<std::string> command_names();
const char* process_state_name(msg::ProcessState s);
const char* stand_state_name(msg::StandState s);

}  // namespace dw::dds
