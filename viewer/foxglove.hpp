#pragma once
// The Foxglove WebSocket protocol (github.com/foxglove/ws-protocol, docs/spec.md), the server's
// side of it as the viewer speaks it: read-only — it advertises channels and sends their messages,
// takes subscriptions, and refuses every client operation that would publish, call or set
// anything. Pure functions: the socket is server.hpp's.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <variant>
#include <vector>

namespace dw::viewer {

// The subprotocols the viewer speaks, the one a client offered first among them is echoed:
// Foxglove's two names for its protocol, and the page's own (JSON text frames, page.hpp).
inline constexpr std::string_view kFoxgloveSdk = "foxglove.sdk.v1";
inline constexpr std::string_view kFoxgloveWebsocket = "foxglove.websocket.v1";
inline constexpr std::string_view kPageProtocol = "dw.json.v1";
enum class Dialect { foxglove, page };
struct Chosen {
    std::string subprotocol;
    Dialect dialect = Dialect::foxglove;
};
// From a Sec-WebSocket-Protocol header ("a, b, c"): the first the viewer speaks, or none.
std::optional<Chosen> choose_subprotocol(std::string_view offered);

// One lab topic as a channel: CDR payloads described by their OMG IDL (as the recorder writes MCAP).
struct Channel {
    std::uint32_t id = 0;
    std::string topic;        // rt/<namespace>/<suffix>
    std::string schema_name;  // the IDL root type, e.g. dw::msg::WrenchStamped
    std::string schema;       // the IDL document (includes inlined)
};

std::string server_info(std::string_view name, std::string_view session_id);
std::string advertise(std::span<const Channel> channels);
enum class StatusLevel { info = 0, warning = 1, error = 2 };
std::string status(StatusLevel level, std::string_view message);

// Binary server messages: MessageData (opcode 1) and Time (opcode 2), little-endian.
inline constexpr std::uint8_t kMessageDataOpcode = 1;
inline constexpr std::uint8_t kTimeOpcode = 2;
std::vector<std::uint8_t> message_data(std::uint32_t subscription, std::uint64_t log_time_ns,
                                       std::span<const std::uint8_t> payload);
std::vector<std::uint8_t> time_message(std::uint64_t now_ns);

// j as JSON text, never throwing: bytes that are no UTF-8 (a hostile sample's string, a client's
// name cut short) become U+FFFD.
std::string json_text(const nlohmann::json& j);

// A client's text message, as the viewer takes it.
struct Subscribe {
    std::vector<std::pair<std::uint32_t, std::uint32_t>> subscriptions;  // (subscription id, channel id)
};
struct Unsubscribe {
    std::vector<std::uint32_t> subscription_ids;
};
struct Refused {
    std::string why;  // one line, for a status message back to the client
};
using ClientMessage = std::variant<Subscribe, Unsubscribe, Refused>;
// Never throws: malformed JSON, a missing field or an operation the viewer does not take is Refused.
ClientMessage parse_client(std::string_view text);

}  // namespace dw::viewer
