#include "viewer/server.hpp"

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/address.hpp>
#include <boost/asio/post.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <future>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "viewer/page.hpp"
#include "viewer/session.hpp"

namespace dw::viewer {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;

namespace {
constexpr std::chrono::seconds kHttpTimeout{10};
constexpr std::uint32_t kMaxHeaderBytes = 16 * 1024;
constexpr std::uint64_t kMaxBodyBytes = 1024;  // the viewer takes no request bodies
// The kernel's send buffer per connection: what a client has not read waits in its outbox (bounded,
// oldest sensor frames dropped), not in megabytes of socket buffer that would only add latency.
constexpr int kSendBufferBytes = 64 * 1024;
}  // namespace

struct Server::Impl {
    Impl(Hub& h, const ServerOptions& opts) : hub(h), o(opts) {}
    void listen();
    void accept();
    void upgraded(tcp::socket socket, http::request<http::string_body> req, const Chosen& chosen);

    asio::io_context io{1};  // first: destroyed last, after everything that holds its sockets
    Hub& hub;
    ServerOptions o;
    tcp::acceptor acceptor{io};
    std::vector<std::shared_ptr<Session>> sessions;  // the server's thread only (stats: under sessions_mutex)
    mutable std::mutex sessions_mutex;
    std::thread thread;
};

namespace {
// One HTTP request: the page's files, or the upgrade to a WebSocket.
class HttpRequest : public std::enable_shared_from_this<HttpRequest> {
public:
    HttpRequest(tcp::socket s, Server::Impl& server) : stream_(std::move(s)), server_(server) {}
    void start() {
        parser_.header_limit(kMaxHeaderBytes);
        parser_.body_limit(kMaxBodyBytes);
        stream_.expires_after(kHttpTimeout);
        http::async_read(stream_, buffer_, parser_, [self = shared_from_this()](beast::error_code ec, std::size_t) {
            if (!ec) self->route();
        });
    }

private:
    void route() {
        auto req = parser_.release();
        if (websocket::is_upgrade(req)) {
            const auto offered = req[http::field::sec_websocket_protocol];
            const auto chosen = choose_subprotocol(std::string_view(offered.data(), offered.size()));
            if (!chosen)
                return respond(http::status::bad_request, "text/plain",
                               log::cat("offer a subprotocol this viewer speaks: ", kFoxgloveWebsocket, ", ",
                                        kFoxgloveSdk, " or ", kPageProtocol, "\n"));
            stream_.expires_never();
            return server_.upgraded(stream_.release_socket(), std::move(req), *chosen);
        }
        if (req.method() != http::verb::get)
            return respond(http::status::method_not_allowed, "text/plain", "GET only\n");
        const auto* f = page_file(std::string_view(req.target().data(), req.target().size()));
        if (!f) return respond(http::status::not_found, "text/plain", "not found\n");
        respond(http::status::ok, f->content_type, std::string(f->body));
    }
    void respond(http::status code, std::string_view type, std::string body) {
        auto res = std::make_shared<http::response<http::string_body>>(code, 11);
        res->set(http::field::server, "dw-viewer");
        res->set(http::field::content_type, std::string(type));
        res->set(http::field::cache_control, "no-store");
        res->keep_alive(false);
        res->body() = std::move(body);
        res->prepare_payload();
        http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code, std::size_t) {
            beast::error_code ignored;
            self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
        });
    }

    beast::tcp_stream stream_;
    Server::Impl& server_;
    beast::flat_buffer buffer_;
    http::request_parser<http::string_body> parser_;
};
}  // namespace

void Server::Impl::listen() {
    beast::error_code ec;
    const auto address = asio::ip::make_address(o.bind, ec);
    if (ec) throw InputError(log::cat("--bind '", o.bind, "': not an IP address"));
    const tcp::endpoint at(address, o.port);
    acceptor.open(at.protocol(), ec);
    if (!ec) acceptor.set_option(asio::socket_base::reuse_address(true), ec);
    if (!ec) acceptor.bind(at, ec);
    if (!ec) acceptor.listen(asio::socket_base::max_listen_connections, ec);
    if (ec) throw RuntimeError(log::cat("cannot listen on ", o.bind, ":", o.port, ": ", ec.message()));
}

void Server::Impl::accept() {
    acceptor.async_accept([this](beast::error_code ec, tcp::socket socket) {
        if (ec) return;  // closed: the server is going away
        socket.set_option(tcp::no_delay(true), ec);
        socket.set_option(asio::socket_base::send_buffer_size(kSendBufferBytes), ec);
        std::make_shared<HttpRequest>(std::move(socket), *this)->start();
        accept();
    });
}

void Server::Impl::upgraded(tcp::socket socket, http::request<http::string_body> req, const Chosen& chosen) {
    auto s = std::make_shared<Session>(std::move(socket), hub, o.name, chosen);
    {
        std::lock_guard lock(sessions_mutex);
        std::erase_if(sessions, [](const auto& e) { return e->closed(); });
        sessions.push_back(s);
    }
    s->start(std::move(req));
}

Server::Server(Hub& hub, const ServerOptions& o) : impl_(std::make_unique<Impl>(hub, o)) {
    impl_->listen();
    impl_->accept();
    impl_->thread = std::thread([this] {
        for (;;) {  // a handler's exception ends that handler, never the server
            try {
                impl_->io.run();
                return;
            } catch (const std::exception& e) {
                log::error("viewer: ", e.what(), " (that client's request dropped; serving on)");
            }
        }
    });
}

Server::~Server() {
    std::promise<void> done;
    asio::post(impl_->io, [this, &done] {
        beast::error_code ignored;
        impl_->acceptor.close(ignored);
        std::lock_guard lock(impl_->sessions_mutex);
        for (const auto& s : impl_->sessions) s->close();
        done.set_value();
    });
    done.get_future().wait();
    impl_->io.stop();
    impl_->thread.join();
}

std::uint16_t Server::port() const { return impl_->acceptor.local_endpoint().port(); }

std::string Server::url() const { return log::cat("http://", impl_->o.bind, ":", port(), "/"); }

ServerStats Server::stats() const {
    ServerStats st;
    std::lock_guard lock(impl_->sessions_mutex);
    for (const auto& s : impl_->sessions) {
        st.frames += s->frames();
        st.dropped += s->outbox().dropped();
        if (s->closed()) continue;
        ++st.clients;
        st.queued_bytes += s->outbox().bytes();
    }
    return st;
}

}  // namespace dw::viewer
