#include "dds/topics.hpp"

#include <algorithm>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::dds {

std::vector<std::string> all_topics() {
    std::vector<std::string> out;
    topics::for_each([&](const auto& spec) { out.emplace_back(spec.suffix); });
    return out;
}

std::vector<std::string> select_topics(const std::vector<std::string>& requested, const std::string& ns) {
    const auto all = all_topics();
    if (requested.empty()) return all;
    std::vector<std::string> out;
    const std::string prefix = "rt/" + ns + "/";
    for (const auto& r : requested) {
        if (r == "all") return all;
        std::string suffix = r.rfind(prefix, 0) == 0 ? r.substr(prefix.size()) : r;
        if (std::find(all.begin(), all.end(), suffix) == all.end()) {
            throw InputError(log::cat("unknown topic '", r, "' (dw-probe list shows the lab's topics)"));
        }
        if (std::find(out.begin(), out.end(), suffix) == out.end()) out.push_back(suffix);
    }
    return out;
}

}  // namespace dw::dds

namespace dw::dds {

std::string_view role_name(Role r) {
    for (const auto& i : kRoles)
        if (i.role == r) return i.name;
    return "?";
}

std::optional<Role> role_named(std::string_view name) {
    for (const auto& i : kRoles)
        if (i.name == name) return i.role;
    return std::nullopt;
}

std::optional<Role> role_of_executable(std::string_view executable) {
    const auto slash = executable.rfind('/');
    if (slash != std::string_view::npos) executable.remove_prefix(slash + 1);
    for (const auto& i : kRoles)
        if (i.executable == executable) return i.role;
    return std::nullopt;
}

}  // namespace dw::dds
