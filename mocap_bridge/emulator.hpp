#pragma once
// A NatNet server emulator (a test tool, and the `sim` source's back end): answers CONNECT with
// SERVERINFO and REQUEST_MODELDEF with MODELDEF, and streams real-format FRAMEOFDATA packets by
// unicast to every connected client at the chosen version and rate, with faults on demand.
#include <atomic>
#include <functional>
#include <mutex>
#include <random>
#include <thread>
#include <vector>

#include "core/clock.hpp"
#include "flight/flight.hpp"
#include "mocap_bridge/natnet.hpp"
#include "mocap_bridge/udp.hpp"

namespace dw::natnet {

struct BodyPose {
    std::array<double, 3> ned{};              // world NED [m]
    std::array<double, 4> q_ned{1, 0, 0, 0};  // w, x, y, z body -> NED
};

struct TrackingLoss {
    int body = 0;
    double start_s = 0, duration_s = 0;
};

// A hostile Motive (issue 70): this many more bodies every frame, each with an id never sent before
// and in no model definition; a frame clock (the frame's timestamp) that stands still; and every
// kHostileEvery frames one more packet, each kind in turn: a frame cut short, an oversized one (the
// largest datagram, its counts garbage), and a frame whose bodies (the named ones, tracked) and
// timestamp are NaN, ±inf or ±3.4e38.
struct Hostility {
    int new_ids_per_frame = 0;
    bool frozen_clock = false;
    bool packets = false;
};
inline constexpr Range kNewIdsPerFrameRange{0, 100, "bodies"};
inline constexpr std::int32_t kHostileEvery = 5;  // at 180 Hz, 36 hostile packets a second

struct EmulatorOptions {
    std::string ip = "127.0.0.1";
    std::uint16_t port = 1510;  // command port; 0 = any free port
    Version version{4, 1};
    double rate_hz = 180.0;
    std::uint64_t clock_frequency = 10'000'000;  // host ticks per second
    double latency_s = 0.004;                    // mid-exposure to transmit
    double drop_probability = 0.0;               // frames not sent (the bridge must see the gap)
    std::vector<TrackingLoss> losses;
    std::vector<std::string> names{flight::kSufferer, "v1", "v2", "v3"};
    bool other_sections = true;  // marker sets, skeletons, assets, ... to skip
    Hostility hostile;
    std::uint64_t seed = 1;
    // Where body i is at time t (seconds since start); default: the sufferer on the stand and
    // the others circling above it.
    std::function<BodyPose(int body, double t)> motion;
};

class NatNetEmulator {
public:
    explicit NatNetEmulator(const EmulatorOptions& options);
    ~NatNetEmulator();  // stops
    std::uint16_t port() const { return socket_.port(); }
    std::uint64_t frames_sent() const { return sent_; }
    std::size_t clients() const;
    void stop();

private:
    void loop();
    void handle(const std::vector<std::uint8_t>& packet, const Endpoint& from);
    std::vector<std::uint8_t> frame(std::int32_t number, double t);
    std::vector<std::uint8_t> hostile_packet(std::int32_t number, double t, std::mt19937_64& rng);

    EmulatorOptions options_;
    UdpSocket socket_;
    mutable std::mutex mutex_;
    std::vector<Endpoint> clients_;
    std::atomic<bool> stop_{false};
    std::atomic<std::uint64_t> sent_{0};
    Nanos start_ns_ = 0;
    std::thread thread_;
};

// Motive's axes (Y up) from NED with the default axis map n = x, e = z, d = -y.
std::array<float, 3> ned_to_motive(const std::array<double, 3>& ned);

}  // namespace dw::natnet
