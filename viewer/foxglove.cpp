#include "viewer/foxglove.hpp"

#include <nlohmann/json.hpp>

#include "core/log.hpp"

namespace dw::viewer {

namespace {
// Splits "a, b ,c" at commas, trimming spaces and tabs.
std::vector<std::string_view> tokens(std::string_view s) {
    std::vector<std::string_view> out;
    while (!s.empty()) {
        const auto comma = s.find(',');
        auto t = s.substr(0, comma);
        while (!t.empty() && (t.front() == ' ' || t.front() == '\t')) t.remove_prefix(1);
        while (!t.empty() && (t.back() == ' ' || t.back() == '\t')) t.remove_suffix(1);
        if (!t.empty()) out.push_back(t);
        if (comma == std::string_view::npos) break;
        s.remove_prefix(comma + 1);
    }
    return out;
}

void put_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
}
void put_u64(std::vector<std::uint8_t>& out, std::uint64_t v) {
    for (int b = 0; b < 8; ++b) out.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
}

// A JSON number that is a whole uint32, or nullopt.
std::optional<std::uint32_t> u32(const nlohmann::json& j) {
    if (!j.is_number_unsigned() && !(j.is_number_integer() && j.get<std::int64_t>() >= 0)) return std::nullopt;
    const auto v = j.get<std::uint64_t>();
    if (v > 0xffffffffu) return std::nullopt;
    return static_cast<std::uint32_t>(v);
}

ClientMessage parse_subscribe(const nlohmann::json& j) {
    const auto it = j.find("subscriptions");
    if (it == j.end() || !it->is_array()) return Refused{"subscribe: expected an array 'subscriptions'"};
    Subscribe s;
    for (const auto& e : *it) {
        if (!e.is_object() || !e.contains("id") || !e.contains("channelId"))
            return Refused{"subscribe: each subscription needs 'id' and 'channelId'"};
        const auto id = u32(e["id"]), channel = u32(e["channelId"]);
        if (!id || !channel) return Refused{"subscribe: 'id' and 'channelId' must be whole numbers below 2^32"};
        s.subscriptions.emplace_back(*id, *channel);
    }
    return s;
}

ClientMessage parse_unsubscribe(const nlohmann::json& j) {
    const auto it = j.find("subscriptionIds");
    if (it == j.end() || !it->is_array()) return Refused{"unsubscribe: expected an array 'subscriptionIds'"};
    Unsubscribe u;
    for (const auto& e : *it) {
        const auto id = u32(e);
        if (!id) return Refused{"unsubscribe: subscription ids must be whole numbers below 2^32"};
        u.subscription_ids.push_back(*id);
    }
    return u;
}
}  // namespace

std::string json_text(const nlohmann::json& j) {
    return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

std::optional<Chosen> choose_subprotocol(std::string_view offered) {
    for (const auto t : tokens(offered)) {
        if (t == kFoxgloveSdk || t == kFoxgloveWebsocket) return Chosen{std::string(t), Dialect::foxglove};
        if (t == kPageProtocol) return Chosen{std::string(t), Dialect::page};
    }
    return std::nullopt;
}

std::string server_info(std::string_view name, std::string_view session_id) {
    return json_text(nlohmann::json{{"op", "serverInfo"},
                                    {"name", name},
                                    {"capabilities", nlohmann::json::array({"time"})},
                                    {"supportedEncodings", nlohmann::json::array()},
                                    {"metadata", nlohmann::json::object()},
                                    {"sessionId", session_id}});
}

std::string advertise(std::span<const Channel> channels) {
    nlohmann::json list = nlohmann::json::array();
    for (const auto& c : channels)
        list.push_back({{"id", c.id},
                        {"topic", c.topic},
                        {"encoding", "cdr"},
                        {"schemaName", c.schema_name},
                        {"schema", c.schema},
                        {"schemaEncoding", "omgidl"}});
    return json_text(nlohmann::json{{"op", "advertise"}, {"channels", list}});
}

std::string status(StatusLevel level, std::string_view message) {
    return json_text(nlohmann::json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}});
}

std::vector<std::uint8_t> message_data(std::uint32_t subscription, std::uint64_t log_time_ns,
                                       std::span<const std::uint8_t> payload) {
    std::vector<std::uint8_t> out;
    out.reserve(1 + 4 + 8 + payload.size());
    out.push_back(kMessageDataOpcode);
    put_u32(out, subscription);
    put_u64(out, log_time_ns);
    out.insert(out.end(), payload.begin(), payload.end());
    return out;
}

std::vector<std::uint8_t> time_message(std::uint64_t now_ns) {
    std::vector<std::uint8_t> out{kTimeOpcode};
    put_u64(out, now_ns);
    return out;
}

ClientMessage parse_client(std::string_view text) {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object()) return Refused{"not a JSON object"};
    const auto op = j.find("op");
    if (op == j.end() || !op->is_string()) return Refused{"no 'op'"};
    const auto name = op->get<std::string>();
    if (name == "subscribe") return parse_subscribe(j);
    if (name == "unsubscribe") return parse_unsubscribe(j);
    return Refused{
        log::cat("'", name.substr(0, 40), "' is not taken: this viewer is read-only (subscribe, unsubscribe)")};
}

}  // namespace dw::viewer
