#pragma once
// A small UDP socket for NatNet's command and data channels (IPv4).
#include <netinet/in.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "core/numbers.hpp"

namespace dw::natnet {

inline constexpr Range kPortRange{0, 65535};             // a UDP port (0 = any free one where allowed)
inline constexpr std::size_t kMaxDatagramBytes = 65507;  // the largest UDP payload over IPv4

struct Endpoint {
    sockaddr_in addr{};
    static Endpoint make(const std::string& ip, std::uint16_t port);  // throws dw::InputError
    std::string str() const;
    bool operator==(const Endpoint& o) const;
};

class UdpSocket {
public:
    // Binds ip:port (port 0 = any); throws dw::RuntimeError.
    UdpSocket(const std::string& ip, std::uint16_t port);
    ~UdpSocket();
    UdpSocket(const UdpSocket&) = delete;
    UdpSocket& operator=(const UdpSocket&) = delete;
    void send_to(const Endpoint& to, std::span<const std::uint8_t> data);
    // Waits up to timeout_ms for one datagram; nullopt on timeout.
    std::optional<std::vector<std::uint8_t>> receive(int timeout_ms, Endpoint* from = nullptr);
    std::uint16_t port() const;
    void join_multicast(const std::string& group, const std::string& interface_ip);

private:
    int fd_ = -1;
};

}  // namespace dw::natnet
