#pragma once
// OptiTrack NatNet packets (3.0, 3.1, 4.0, 4.1 bitstreams), from the published layout
// (../shared/SPECS.md §2; NaturalPoint's PacketClient sample was read, not copied). Only rigid
// bodies are kept; every other section is skipped by its size (4.1+) or its structure. Parsing
// never reads outside the packet: a malformed one is a dw::InputError saying where.
#include <array>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace dw::natnet {

enum MessageId : std::uint16_t {
    kConnect = 0,
    kServerInfo = 1,
    kRequest = 2,
    kResponse = 3,
    kRequestModelDef = 4,
    kModelDef = 5,
    kRequestFrameOfData = 6,
    kFrameOfData = 7,
    kMessageString = 8,
    kDisconnect = 9,
    kKeepAlive = 10,
    kUnrecognizedRequest = 100,
};

struct Version {
    int major = 4, minor = 1;
    bool at_least(int ma, int mi) const { return major > ma || (major == ma && minor >= mi); }
};

struct RigidBody {
    std::int32_t id = 0;
    std::array<float, 3> position{};               // Motive frame (Y up), metres
    std::array<float, 4> orientation{0, 0, 0, 1};  // qx, qy, qz, qw as on the wire
    float mean_error = 0;
    bool tracking_valid = false;  // params bit 0
};

struct FrameOfData {
    std::int32_t frame_number = 0;
    std::vector<RigidBody> bodies;  // top-level rigid bodies
    std::uint32_t timecode = 0, timecode_sub = 0;
    double timestamp_s = 0;                                           // seconds since the software started
    std::uint64_t mid_exposure = 0, data_received = 0, transmit = 0;  // host ticks (3.0+)
    std::uint32_t precision_s = 0, precision_frac = 0;                // 4.1+
    std::int16_t params = 0;
};

struct ServerInfo {
    std::string app_name;
    std::array<std::uint8_t, 4> app_version{};
    Version natnet;
    std::uint64_t clock_frequency = 0;  // high-resolution ticks per second
    std::uint16_t data_port = 1511;
    bool multicast = false;
    std::array<std::uint8_t, 4> multicast_group{239, 255, 42, 99};
};

struct RigidBodyDescription {
    std::string name;
    std::int32_t id = 0, parent = -1;
    std::array<float, 3> offset{};
    std::vector<std::array<float, 3>> markers;
    std::vector<std::string> marker_names;  // 4.0+
};

struct ModelDef {
    std::vector<RigidBodyDescription> rigid_bodies;  // top-level ones
    std::vector<std::string> marker_sets;
    int skipped = 0;  // datasets of other kinds
};

// Packet = header (message id u16, payload bytes u16) + payload.
std::uint16_t message_id(std::span<const std::uint8_t> packet);               // throws on a short packet
std::span<const std::uint8_t> payload(std::span<const std::uint8_t> packet);  // checks the length

FrameOfData parse_frame(std::span<const std::uint8_t> payload, Version v);
ModelDef parse_modeldef(std::span<const std::uint8_t> payload, Version v);
ServerInfo parse_server_info(std::span<const std::uint8_t> payload);

// Writers (the emulator and the tests): complete packets, header included. A frame also carries
// the sections a bridge must skip (a marker set, labeled markers, a skeleton, an asset in 4.1, a
// force plate and a device) when `with_other_sections` is set.
std::vector<std::uint8_t> build_frame(const FrameOfData& f, Version v, bool with_other_sections = true);
std::vector<std::uint8_t> build_modeldef(const ModelDef& m, Version v);
std::vector<std::uint8_t> build_server_info(const ServerInfo& s);
std::vector<std::uint8_t> build_simple(MessageId id, std::span<const std::uint8_t> payload = {});
std::vector<std::uint8_t> build_connect();

}  // namespace dw::natnet
