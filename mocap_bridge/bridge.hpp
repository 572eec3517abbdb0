#pragma once
// The mocap bridge: a NatNet client (unicast command channel, frames received on it, keepalives),
// and the conversion of each frame to the lab's MocapFrame and per-vehicle VehicleState: Motive's
// Y-up axes to NED, rigid-body names to vehicle names, honest timestamps, per-body velocity robust
// to dropped frames, tracking-lost flags, staleness and dropped-frame counts.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/bounded_map.hpp"
#include "core/clock.hpp"
#include "flight/flight.hpp"
#include "dw/msg/Mocap.h"
#include "dw/msg/Vehicle.h"
#include "mocap_bridge/natnet.hpp"
#include "mocap_bridge/udp.hpp"

namespace dw::natnet {

struct ClientOptions {
    std::string server_ip = "127.0.0.1";
    std::uint16_t command_port = 1510;
    std::string local_ip = "127.0.0.1";
    int connect_timeout_ms = 3000;
};

class NatNetClient {
public:
    explicit NatNetClient(const ClientOptions& o);
    // CONNECT -> SERVERINFO. Throws dw::RuntimeError when no server answers.
    ServerInfo connect();
    ModelDef request_modeldef();
    struct Received {
        FrameOfData frame;
        Nanos receive_wall_ns = 0;
    };
    // The next frame within timeout_ms: packets of other kinds are ignored and malformed ones counted
    // and skipped, and the wait goes on until the deadline. Keepalives are sent about once a second.
    std::optional<Received> next_frame(int timeout_ms);
    std::uint64_t malformed() const { return malformed_; }
    const ServerInfo& server() const { return server_; }

private:
    ClientOptions options_;
    UdpSocket socket_;
    Endpoint server_endpoint_;
    ServerInfo server_;
    Nanos last_keepalive_ = 0;
    std::uint64_t malformed_ = 0;
};

struct AxisMap {
    // Each NED axis as a signed Motive axis: default n = x, e = z, d = -y.
    std::array<int, 3> source{0, 2, 1};
    std::array<int, 3> sign{1, 1, -1};
    static AxisMap parse(const std::string& text);  // "x,z,-y"; throws dw::InputError
    int det() const;                                // +1 for a rotation, -1 for a reflection of the axes
};

// Motive's frame clock (FrameOfData::timestamp_s) is seconds since the software started: a frame
// stamped outside this is refused whole like a non-finite one (issue 70: a frame at 3.4e38 s, then
// one at -3.4e38 s, looked like a Motive restart and reset every body's estimator).
inline constexpr Range kMotiveClockRange{0, 1e9, "s"};  // 31 years of uptime

// A body's recent samples for its velocity: at most this many whatever the clock does (the window,
// 0.03 s, holds 6 at Motive's 180 Hz; a Motive whose clock stands still never ages one out).
inline constexpr std::size_t kMaxRecentSamples = 64;

struct BridgeOptions {
    AxisMap axes;
    std::map<std::string, std::string> names;  // rigid-body name -> vehicle name
    msg::MocapTimestampMode mode = msg::MOCAP_STAMP_COMPENSATED;
    double velocity_window_s = 0.03;  // least-squares velocity over this span
    double reset_gap_s = 0.05;        // a longer gap restarts a body's estimator
};

class FrameConverter {
public:
    FrameConverter(const BridgeOptions& o, const ServerInfo& server, const ModelDef& models);
    struct Output {
        msg::MocapFrame frame;
        std::vector<msg::VehicleState> states;
    };
    // Nothing non-finite or implausible enters the lab (issue 70): such a body is passed on as lost
    // (tracking not valid, no pose) and counted; a frame whose clock is not in kMotiveClockRange is refused whole
    // (`refused`: nothing to publish).
    Output convert(const FrameOfData& f, Nanos receive_wall_ns, bool* refused = nullptr);
    std::uint64_t dropped() const { return dropped_; }
    std::uint64_t implausible() const { return implausible_; }  // bodies and frames refused
    // Bodies whose id no model definition gave (issue 70: a Motive inventing ids every frame): in
    // the frame, but no vehicle state (vehicles/state is keyed by vehicle, kMaxInstances of them).
    std::uint64_t undefined() const { return undefined_; }
    // What it holds per body, for the bound on memory: bodies tracked, velocity samples over all.
    struct Held {
        std::size_t bodies = 0, samples = 0;
    };
    Held held() const;

private:
    struct Track {
        std::vector<std::pair<double, std::array<double, 3>>> recent;  // camera time, NED position
        double last_valid_s = -1;
    };
    double camera_time_s(const FrameOfData& f, Nanos receive_wall_ns);
    // A body in the lab's names and NED axes.
    msg::RigidBody lab_body(const RigidBody& b);
    // Its vehicle state at camera time tc: the pose (held through a loss) and the velocity over the recent samples.
    msg::VehicleState vehicle_state(const msg::RigidBody& r, const msg::Time& stamp, double tc);

    BridgeOptions options_;
    ServerInfo server_;
    std::map<std::int32_t, std::string> names_;
    // At most flight::kMaxBodies: a Motive that sends a new id every frame forgets the oldest.
    BoundedMap<std::int32_t, Track> tracks_{flight::kMaxBodies};
    double last_camera_s_ = -1;  // Motive's frame clock of the last frame
    std::int32_t last_frame_ = -1;
    std::uint64_t dropped_ = 0;
    std::uint64_t implausible_ = 0;
    std::uint64_t undefined_ = 0;
    double clock_offset_s_ = 0;  // clock-sync mode: host wall time - server ticks
    bool have_offset_ = false;
};

}  // namespace dw::natnet
