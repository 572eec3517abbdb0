#include "viewer/session.hpp"

#include <boost/asio/post.hpp>
#include <boost/beast/core/buffers_to_string.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "core/log.hpp"
#include "dds/wire_enums.hpp"

namespace dw::viewer {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;

namespace {
// The wire enums' names by value, for the page (dds/names.hpp: defined once).
template <class E>
nlohmann::json names_of(E last, const char* (*name)(E)) {
    nlohmann::json out = nlohmann::json::array();
    for (int v = 0; v <= static_cast<int>(last); ++v) out.push_back(name(static_cast<E>(v)));
    return out;
}
nlohmann::json enum_names() {
    return {{"phase", names_of(msg::PHASE_ABORTED, dds::phase_name)},
            {"process_state", names_of(msg::PROC_STOPPING, dds::process_state_name)},
            {"stand_state", names_of(msg::STAND_FAULT, dds::stand_state_name)}};
}
}  // namespace

Session::Session(asio::ip::tcp::socket socket, Hub& hub, std::string server_name, Chosen chosen)
    : ws_(std::move(socket)), hub_(hub), server_name_(std::move(server_name)), chosen_(std::move(chosen)) {}

void Session::start(http::request<http::string_body> upgrade) {
    ws_.set_option(websocket::stream_base::timeout::suggested(beast::role_type::server));
    ws_.read_message_max(kMaxClientMessage);
    ws_.set_option(websocket::stream_base::decorator([p = chosen_.subprotocol](websocket::response_type& res) {
        res.set(http::field::sec_websocket_protocol, p);
        res.set(http::field::server, "dw-viewer");
    }));
    ws_.async_accept(upgrade, [self = shared_from_this()](beast::error_code ec) {
        if (ec) return self->close();  // a handshake that failed: no client
        self->opened();
    });
}

void Session::opened() {
    if (chosen_.dialect == Dialect::foxglove) {
        control(server_info(server_name_, log::cat(reinterpret_cast<std::uintptr_t>(this))));
        control(advertise(hub_.channels()));
    } else {
        nlohmann::json topics = nlohmann::json::array();
        for (const auto& c : hub_.channels()) topics.push_back(c.topic);
        control(json_text({{"op", "hello"}, {"name", server_name_}, {"topics", topics}, {"enums", enum_names()}}));
    }
    hub_.attach(shared_from_this());
    read();
    pump();
}

void Session::close() {
    {
        std::lock_guard lock(mutex_);
        closed_ = true;
    }
    hub_.detach(this);
    beast::error_code ec;
    beast::get_lowest_layer(ws_).socket().close(ec);
}

bool Session::closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
}

void Session::read() {
    ws_.async_read(in_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
        if (ec) return self->close();  // the client left, or broke the protocol: its session ends
        if (!self->ws_.got_text())
            self->control(status(StatusLevel::error, "binary client messages are not taken: this viewer is read-only"));
        else self->handle(beast::buffers_to_string(self->in_.data()));
        self->in_.consume(self->in_.size());
        self->read();
        self->pump();
    });
}

void Session::handle(const std::string& text) {
    if (chosen_.dialect == Dialect::page) return handle_page(text);
    const auto m = parse_client(text);
    if (const auto* s = std::get_if<Subscribe>(&m)) return subscribe(*s);
    if (const auto* u = std::get_if<Unsubscribe>(&m)) return unsubscribe(*u);
    control(status(StatusLevel::error, std::get<Refused>(m).why));
}

// The page's one message: {"op": "subscribe", "topics": [full topic names]}.
void Session::handle_page(const std::string& text) {
    const auto j = nlohmann::json::parse(text, nullptr, false);
    if (!j.is_object() || j.value("op", "") != "subscribe" || !j.contains("topics") || !j["topics"].is_array())
        return control(status(StatusLevel::error, "expected {\"op\": \"subscribe\", \"topics\": [...]}"));
    std::set<std::uint32_t> wanted;
    for (const auto& c : hub_.channels())
        for (const auto& t : j["topics"])
            if (t.is_string() && t.get<std::string>() == c.topic) wanted.insert(c.id);
    {
        std::lock_guard lock(mutex_);
        page_channels_ = wanted;
    }
    for (auto c : wanted) hub_.replay(*this, c);
}

void Session::subscribe(const Subscribe& s) {
    std::vector<std::uint32_t> added;
    for (const auto& [id, channel] : s.subscriptions) {
        if (channel == 0 || channel > hub_.channels().size()) {
            control(status(StatusLevel::error, log::cat("subscribe: no channel ", channel)));
            continue;
        }
        std::lock_guard lock(mutex_);
        subscription_of_[channel] = id;
        added.push_back(channel);
    }
    for (auto c : added) hub_.replay(*this, c);
}

void Session::unsubscribe(const Unsubscribe& u) {
    std::lock_guard lock(mutex_);
    for (auto id : u.subscription_ids) std::erase_if(subscription_of_, [&](const auto& e) { return e.second == id; });
}

std::optional<Frame> Session::frame_for(const Sample& s) {
    std::lock_guard lock(mutex_);
    if (closed_) return std::nullopt;
    if (chosen_.dialect == Dialect::foxglove) {
        const auto it = subscription_of_.find(s.channel);
        if (it == subscription_of_.end()) return std::nullopt;
        const auto bytes = message_data(it->second, s.log_time_ns, s.cdr);
        return Frame{true, std::string(bytes.begin(), bytes.end())};
    }
    if (!s.json || !page_channels_.contains(s.channel)) return std::nullopt;
    return Frame{false, log::cat("{\"topic\":\"", s.suffix, "\",\"t\":", s.log_time_ns, ",\"msg\":", *s.json, "}")};
}

void Session::deliver(const Sample& s) {
    auto f = frame_for(s);
    if (!f) return;
    if (s.latest) outbox_.push_latest(s.channel, std::string(s.key), std::move(*f));
    else outbox_.push_stream(std::move(*f));
    schedule();
}

void Session::control(std::string text) {
    if (control_.size() < kMaxControlFrames) control_.push_back({false, std::move(text)});
}

void Session::schedule() {
    {
        std::lock_guard lock(mutex_);
        if (closed_ || scheduled_) return;
        scheduled_ = true;
    }
    asio::post(ws_.get_executor(), [self = shared_from_this()] {
        {
            std::lock_guard lock(self->mutex_);
            self->scheduled_ = false;
        }
        self->pump();
    });
}

void Session::pump() {
    if (writing_ || closed()) return;
    unnoticed_drops_ += outbox_.take_new_drops();
    const auto now = std::chrono::steady_clock::now();
    if (unnoticed_drops_ > 0 && now - last_notice_ >= kDropNoticeEvery) {
        control(status(StatusLevel::warning,
                       log::cat("dropped the ", unnoticed_drops_,
                                " oldest sensor samples: this client reads slower than the lab sends (",
                                outbox_.dropped(), " in all)")));
        unnoticed_drops_ = 0, last_notice_ = now;
    }
    std::optional<Frame> f;
    if (!control_.empty()) f = std::move(control_.front()), control_.pop_front();
    else f = outbox_.pop();
    if (!f) return;
    current_ = std::move(*f);
    writing_ = true;
    ws_.binary(current_.binary);
    ws_.async_write(asio::buffer(current_.bytes), [self = shared_from_this()](beast::error_code ec, std::size_t) {
        self->writing_ = false;
        if (ec) return self->close();
        ++self->frames_;
        self->pump();
    });
}

}  // namespace dw::viewer
