#pragma once
// One WebSocket client of the viewer (server.cpp accepts it): it speaks the Foxglove protocol or
// the page's JSON frames, takes subscriptions, and writes what the hub delivers from its bounded
// outbox, one frame at a time, on the server's thread.
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core/flat_buffer.hpp>
#include <boost/beast/core/tcp_stream.hpp>
#include <boost/beast/http/message.hpp>
#include <boost/beast/http/string_body.hpp>
#include <boost/beast/websocket/stream.hpp>
#include <chrono>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>

#include "viewer/foxglove.hpp"
#include "viewer/hub.hpp"
#include "viewer/outbox.hpp"

namespace dw::viewer {

// At most this many bytes in one client message; this many control frames (greetings, refusals) wait.
inline constexpr std::size_t kMaxClientMessage = 64 * 1024;
inline constexpr std::size_t kMaxControlFrames = 64;
// A client that loses frames is told at most this often.
inline constexpr std::chrono::seconds kDropNoticeEvery{1};

class Session final : public Client, public std::enable_shared_from_this<Session> {
public:
    Session(boost::asio::ip::tcp::socket socket, Hub& hub, std::string server_name, Chosen chosen);
    // Completes the WebSocket handshake of `upgrade` (echoing the chosen subprotocol), then greets.
    void start(boost::beast::http::request<boost::beast::http::string_body> upgrade);
    // No delivery, no write after this (the server is going away); on the server's thread.
    void close();
    bool closed() const;

    void deliver(const Sample& s) override;
    bool wants_json() const override { return chosen_.dialect == Dialect::page; }
    const Outbox& outbox() const { return outbox_; }
    std::uint64_t frames() const { return frames_.load(); }

private:
    void opened();
    void read();
    void handle(const std::string& text);
    void handle_page(const std::string& text);
    void subscribe(const Subscribe& s);
    void unsubscribe(const Unsubscribe& u);
    void control(std::string text);  // a JSON text frame before the outbox's
    void schedule();                 // a pump on the server's thread, once
    void pump();
    std::optional<Frame> frame_for(const Sample& s);

    boost::beast::websocket::stream<boost::beast::tcp_stream> ws_;
    Hub& hub_;
    std::string server_name_;
    Chosen chosen_;
    Outbox outbox_;
    boost::beast::flat_buffer in_;
    std::deque<Frame> control_;  // the server's thread only
    Frame current_;              // being written
    bool writing_ = false;       // the server's thread only
    std::chrono::steady_clock::time_point last_notice_{};
    std::uint64_t unnoticed_drops_ = 0;
    mutable std::mutex mutex_;  // below
    bool closed_ = false, scheduled_ = false;
    std::map<std::uint32_t, std::uint32_t> subscription_of_;  // channel -> Foxglove subscription id
    std::set<std::uint32_t> page_channels_;                   // the page's subscribed channels
    std::atomic<std::uint64_t> frames_{0};
};

}  // namespace dw::viewer
