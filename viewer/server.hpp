#pragma once
// The viewer's one port (issue 72): HTTP for its own page (page.hpp) and WebSocket for the
// Foxglove protocol (foxglove.hpp) and the page's JSON frames, over Boost.Beast on one thread.
// Each client has a bounded outbox (outbox.hpp): a stalled client loses its oldest sensor frames
// and never holds up the lab or the others. Binds to loopback unless told otherwise.
#include <cstdint>
#include <memory>
#include <string>

#include "viewer/hub.hpp"

namespace dw::viewer {

inline constexpr const char* kDefaultBind = "127.0.0.1";
inline constexpr std::uint16_t kDefaultPort = 8765;  // Foxglove's own default

struct ServerOptions {
    std::string bind = kDefaultBind;
    std::uint16_t port = kDefaultPort;  // 0: any free port (tests)
    std::string name = "Downwash Lab viewer";
};

struct ServerStats {
    std::size_t clients = 0;       // connected WebSocket clients
    std::uint64_t frames = 0;      // written to clients
    std::uint64_t dropped = 0;     // stream frames dropped for slow clients, over all clients
    std::size_t queued_bytes = 0;  // waiting in the outboxes now
};

class Server {
public:
    // Listens at once; throws dw::InputError for an address that is not one, dw::RuntimeError when
    // the port cannot be bound.
    Server(Hub& hub, const ServerOptions& o);
    ~Server();
    Server(const Server&) = delete;
    Server& operator=(const Server&) = delete;

    std::uint16_t port() const;
    std::string url() const;  // http://<bind>:<port>/
    ServerStats stats() const;

    struct Impl;

private:
    std::unique_ptr<Impl> impl_;
};

}  // namespace dw::viewer
