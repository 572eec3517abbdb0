#include "dds/msg_json.hpp"

namespace dw::dds {
using nlohmann::json;

namespace {
void flatten_into(const json& j, const std::string& prefix, std::vector<std::pair<std::string, json>>& out) {
    if (j.is_object()) {
        for (const auto& [k, v] : j.items()) flatten_into(v, prefix.empty() ? k : prefix + "." + k, out);
    } else if (j.is_array()) {
        for (std::size_t i = 0; i < j.size(); ++i) flatten_into(j[i], prefix + "[" + std::to_string(i) + "]", out);
    } else {
        out.emplace_back(prefix, j);
    }
}
}  // namespace

std::vector<std::pair<std::string, json>> flatten(const json& j) {
    std::vector<std::pair<std::string, json>> out;
    flatten_into(j, "", out);
    return out;
}

}  // namespace dw::dds
