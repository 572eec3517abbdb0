#include "mocap_bridge/udp.hpp"

#include <arpa/inet.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::natnet {

Endpoint Endpoint::make(const std::string& ip, std::uint16_t port) {
    Endpoint e;
    e.addr.sin_family = AF_INET;
    e.addr.sin_port = htons(port);
    if (inet_pton(AF_INET, ip.c_str(), &e.addr.sin_addr) != 1)
        throw InputError(log::cat("'", ip, "' is not an IPv4 address"));
    return e;
}

std::string Endpoint::str() const {
    char buf[INET_ADDRSTRLEN] = {};
    inet_ntop(AF_INET, &addr.sin_addr, buf, sizeof(buf));
    return log::cat(buf, ":", ntohs(addr.sin_port));
}

bool Endpoint::operator==(const Endpoint& o) const {
    return addr.sin_addr.s_addr == o.addr.sin_addr.s_addr && addr.sin_port == o.addr.sin_port;
}

UdpSocket::UdpSocket(const std::string& ip, std::uint16_t port) {
    fd_ = ::socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    if (fd_ < 0) throw RuntimeError(log::cat("socket: ", std::strerror(errno)));
    int one = 1;
    ::setsockopt(fd_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof(one));
    int buf = 4 << 20;
    ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &buf, sizeof(buf));
    const Endpoint e = Endpoint::make(ip, port);
    if (::bind(fd_, reinterpret_cast<const sockaddr*>(&e.addr), sizeof(e.addr)) != 0) {
        const std::string why = std::strerror(errno);
        ::close(fd_);
        throw RuntimeError(log::cat("cannot bind UDP ", ip, ":", port, ": ", why));
    }
}

UdpSocket::~UdpSocket() {
    if (fd_ >= 0) ::close(fd_);
}

void UdpSocket::send_to(const Endpoint& to, std::span<const std::uint8_t> data) {
    if (::sendto(fd_, data.data(), data.size(), 0, reinterpret_cast<const sockaddr*>(&to.addr), sizeof(to.addr)) < 0) {
        throw RuntimeError(log::cat("sending to ", to.str(), ": ", std::strerror(errno)));
    }
}

std::optional<std::vector<std::uint8_t>> UdpSocket::receive(int timeout_ms, Endpoint* from) {
    pollfd p{fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, timeout_ms);
    if (r <= 0) return std::nullopt;
    std::vector<std::uint8_t> buf(kMaxDatagramBytes);
    sockaddr_in src{};
    socklen_t len = sizeof(src);
    const ssize_t n = ::recvfrom(fd_, buf.data(), buf.size(), 0, reinterpret_cast<sockaddr*>(&src), &len);
    if (n < 0) return std::nullopt;
    buf.resize(static_cast<std::size_t>(n));
    if (from) from->addr = src;
    return buf;
}

std::uint16_t UdpSocket::port() const {
    sockaddr_in a{};
    socklen_t len = sizeof(a);
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    return ntohs(a.sin_port);
}

void UdpSocket::join_multicast(const std::string& group, const std::string& interface_ip) {
    ip_mreq m{};
    inet_pton(AF_INET, group.c_str(), &m.imr_multiaddr);
    inet_pton(AF_INET, interface_ip.c_str(), &m.imr_interface);
    if (::setsockopt(fd_, IPPROTO_IP, IP_ADD_MEMBERSHIP, &m, sizeof(m)) != 0) {
        throw RuntimeError(log::cat("cannot join multicast ", group, " on ", interface_ip, ": ", std::strerror(errno)));
    }
}

}  // namespace dw::natnet
