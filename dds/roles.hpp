#pragma once
// Who takes part in the lab: one role per lab executable, plus the people. The topic registry
// says which roles produce and consume each topic; the lab's DDS Security permissions are
// generated from it (dw-lab keys), so a process may publish exactly what it produces.
#include <array>
#include <optional>
#include <string_view>

namespace dw::dds {

enum class Role : unsigned {
    stand_agent = 1u << 0,
    mocap_bridge = 1u << 1,
    planner = 1u << 2,
    predictor = 1u << 3,
    recorder = 1u << 4,
    launcher = 1u << 5,   // dw-lab: starts the processes, shows their status
    operator_ = 1u << 6,  // a person's tools (dw-probe): watch everything, command the experiment
    viewer = 1u << 7,     // dw-viewer: reads every topic, publishes nothing (not even a heartbeat)
};
using Roles = unsigned;
constexpr Roles operator|(Role a, Role b) { return static_cast<Roles>(a) | static_cast<Roles>(b); }
constexpr Roles operator|(Roles a, Role b) { return a | static_cast<Roles>(b); }
constexpr bool has(Roles set, Role r) { return (set & static_cast<Roles>(r)) != 0; }

struct RoleInfo {
    Role role;
    std::string_view name;        // the identity's default name
    std::string_view executable;  // the lab executable that plays it
};
inline constexpr std::array<RoleInfo, 8> kRoles{{
    {Role::stand_agent, "stand_agent", "dw-stand-agent"},
    {Role::mocap_bridge, "mocap_bridge", "dw-mocap-bridge"},
    {Role::planner, "planner", "dw-planner"},
    {Role::predictor, "predictor", "dw-predictor"},
    {Role::recorder, "recorder", "dw-recorder"},
    {Role::launcher, "launcher", "dw-lab"},
    {Role::operator_, "operator", "dw-probe"},
    {Role::viewer, "viewer", "dw-viewer"},
}};
inline constexpr Roles kEveryRole = [] {
    Roles all = 0;
    for (const auto& r : kRoles) all |= static_cast<Roles>(r.role);
    return all;
}();
// The roles that only read: their permissions grant no topic to publish.
inline constexpr Roles kReadOnlyRoles = static_cast<Roles>(Role::viewer);
inline constexpr Roles kEveryPublisher = kEveryRole & ~kReadOnlyRoles;

std::string_view role_name(Role r);
std::optional<Role> role_named(std::string_view name);
std::optional<Role> role_of_executable(std::string_view executable);  // its file name: dw-recorder -> recorder

}  // namespace dw::dds
