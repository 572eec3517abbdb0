#include "mocap_bridge/natnet.hpp"

#include <cstring>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::natnet {
namespace {

class In {
public:
    explicit In(std::span<const std::uint8_t> d) : d_(d) {}
    template <class T>
    T get(const char* what) {
        need(sizeof(T), what);
        T v;
        std::memcpy(&v, d_.data() + pos_, sizeof(T));
        pos_ += sizeof(T);
        return v;
    }
    std::int32_t count(const char* what, std::size_t min_item_bytes) {
        const auto n = get<std::int32_t>(what);
        // A count can never promise more items than bytes remain: oversized counts stop here.
        if (n < 0 || static_cast<std::size_t>(n) * min_item_bytes > remaining()) {
            fail(log::cat(what, " count ", n, " does not fit the ", remaining(), " bytes left"));
        }
        return n;
    }
    std::string cstr(const char* what) {
        const auto* begin = d_.data() + pos_;
        const void* nul = std::memchr(begin, 0, remaining());
        if (nul == nullptr) fail(log::cat(what, ": string without its terminating NUL"));
        const std::size_t len = static_cast<std::size_t>(static_cast<const std::uint8_t*>(nul) - begin);
        std::string s(reinterpret_cast<const char*>(begin), len);
        pos_ += len + 1;
        return s;
    }
    void skip(std::size_t n, const char* what) {
        need(n, what);
        pos_ += n;
    }
    std::size_t remaining() const { return d_.size() - pos_; }
    std::size_t pos() const { return pos_; }
    [[noreturn]] void fail(const std::string& what) const {
        throw InputError(log::cat("NatNet packet byte ", pos_, ": ", what));
    }

private:
    void need(std::size_t n, const char* what) const {
        if (n > remaining()) fail(log::cat(what, ": needs ", n, " bytes, ", remaining(), " left (truncated)"));
    }
    std::span<const std::uint8_t> d_;
    std::size_t pos_ = 0;
};

class Out {
public:
    template <class T>
    void put(T v) {
        const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
        b.insert(b.end(), p, p + sizeof(T));
    }
    void cstr(const std::string& s) {
        b.insert(b.end(), s.begin(), s.end());
        b.push_back(0);
    }
    // Section sizes (4.1+): reserve, then fill once the section is written.
    std::size_t reserve_size() {
        put<std::int32_t>(0);
        return b.size();
    }
    void fill_size(std::size_t after) {
        const auto n = static_cast<std::int32_t>(b.size() - after);
        std::memcpy(b.data() + after - 4, &n, 4);
    }
    std::vector<std::uint8_t> b;
};

// A rigid body as in frames, v3+: 38 bytes.
RigidBody read_body(In& in, Version v) {
    RigidBody r;
    r.id = in.get<std::int32_t>("rigid body id");
    for (auto& x : r.position) x = in.get<float>("rigid body position");
    for (auto& x : r.orientation) x = in.get<float>("rigid body orientation");
    if (!v.at_least(3, 0)) {  // older bitstreams carried the markers here
        const auto n = in.count("rigid body markers", 12);
        in.skip(static_cast<std::size_t>(n) * (12 + 4 + 4), "rigid body markers");
    }
    r.mean_error = in.get<float>("rigid body mean error");
    r.tracking_valid = (in.get<std::int16_t>("rigid body params") & 0x01) != 0;
    return r;
}

void write_body(Out& o, const RigidBody& r) {
    o.put(r.id);
    for (float x : r.position) o.put(x);
    for (float x : r.orientation) o.put(x);
    o.put(r.mean_error);
    o.put<std::int16_t>(r.tracking_valid ? 1 : 0);
}

// Skips a section the bridge does not use: by its size (4.1+) or by walking it.
template <class Walk>
void skip_section(In& in, Version v, const char* what, std::size_t min_item, Walk&& walk) {
    const auto n = in.count(what, min_item);
    if (v.at_least(4, 1)) {
        const auto size = in.get<std::int32_t>(what);
        if (size < 0) in.fail(log::cat(what, ": negative section size"));
        in.skip(static_cast<std::size_t>(size), what);
        return;
    }
    for (std::int32_t i = 0; i < n; ++i) walk(in);
}

void skip_channels(In& in) {  // force plates and devices
    in.get<std::int32_t>("device id");
    const auto channels = in.count("device channels", 4);
    for (std::int32_t c = 0; c < channels; ++c) {
        const auto frames = in.count("device frames", 4);
        in.skip(static_cast<std::size_t>(frames) * 4, "device samples");
    }
}

}  // namespace

std::uint16_t message_id(std::span<const std::uint8_t> packet) {
    if (packet.size() < 4)
        throw InputError(log::cat("NatNet packet of ", packet.size(), " bytes: shorter than its header"));
    std::uint16_t id = 0;
    std::memcpy(&id, packet.data(), 2);
    return id;
}

std::span<const std::uint8_t> payload(std::span<const std::uint8_t> packet) {
    message_id(packet);
    std::uint16_t n = 0;
    std::memcpy(&n, packet.data() + 2, 2);
    if (n > packet.size() - 4)
        throw InputError(log::cat("NatNet packet says ", n, " payload bytes, carries ", packet.size() - 4));
    return packet.subspan(4, n);
}

FrameOfData parse_frame(std::span<const std::uint8_t> data, Version v) {
    In in(data);
    FrameOfData f;
    f.frame_number = in.get<std::int32_t>("frame number");
    skip_section(in, v, "marker sets", 5, [](In& s) {
        s.cstr("marker set name");
        const auto m = s.count("marker set markers", 12);
        s.skip(static_cast<std::size_t>(m) * 12, "marker set markers");
    });
    skip_section(in, v, "unlabeled markers", 12, [](In& s) { s.skip(12, "unlabeled marker"); });
    {
        const auto n = in.count("rigid bodies", 38);
        if (v.at_least(4, 1)) in.get<std::int32_t>("rigid bodies size");
        for (std::int32_t i = 0; i < n; ++i) f.bodies.push_back(read_body(in, v));
    }
    skip_section(in, v, "skeletons", 8, [&](In& s) {
        s.get<std::int32_t>("skeleton id");
        const auto n = s.count("skeleton bodies", 38);
        for (std::int32_t i = 0; i < n; ++i) read_body(s, v);
    });
    if (v.at_least(4, 1)) {  // assets exist only from 4.1, always with their size
        in.count("assets", 4);
        const auto size = in.get<std::int32_t>("assets size");
        if (size < 0) in.fail("assets: negative section size");
        in.skip(static_cast<std::size_t>(size), "assets");
    }
    skip_section(in, v, "labeled markers", 26, [&](In& s) { s.skip(v.at_least(3, 0) ? 26 : 22, "labeled marker"); });
    skip_section(in, v, "force plates", 8, skip_channels);
    skip_section(in, v, "devices", 8, skip_channels);
    if (!v.at_least(3, 0)) in.get<float>("latency");
    f.timecode = in.get<std::uint32_t>("timecode");
    f.timecode_sub = in.get<std::uint32_t>("timecode sub");
    f.timestamp_s = in.get<double>("timestamp");
    if (v.at_least(3, 0)) {
        f.mid_exposure = in.get<std::uint64_t>("camera mid-exposure");
        f.data_received = in.get<std::uint64_t>("camera data received");
        f.transmit = in.get<std::uint64_t>("transmit timestamp");
    }
    if (v.at_least(4, 1)) {
        f.precision_s = in.get<std::uint32_t>("precision timestamp");
        f.precision_frac = in.get<std::uint32_t>("precision timestamp fraction");
    }
    f.params = in.get<std::int16_t>("frame params");
    in.get<std::int32_t>("end of data");
    return f;
}

namespace {

RigidBodyDescription read_rigid_description(In& s, Version v) {
    RigidBodyDescription d;
    d.name = s.cstr("rigid body name");
    d.id = s.get<std::int32_t>("rigid body id");
    d.parent = s.get<std::int32_t>("rigid body parent");
    for (auto& x : d.offset) x = s.get<float>("rigid body offset");
    if (v.at_least(4, 2)) s.skip(16, "rigid body offset rotation");
    if (v.at_least(3, 0)) {
        const auto markers = s.count("rigid body markers", 16);
        for (std::int32_t k = 0; k < markers; ++k) {
            std::array<float, 3> p{};
            for (auto& x : p) x = s.get<float>("marker position");
            d.markers.push_back(p);
        }
        s.skip(static_cast<std::size_t>(markers) * 4, "marker labels");
        if (v.at_least(4, 0)) {
            for (std::int32_t k = 0; k < markers; ++k) d.marker_names.push_back(s.cstr("marker name"));
        }
    }
    return d;
}

// A dataset of a description before NatNet 4.1 (no size): rigid bodies are kept, the rest
// skipped by their structure.
void read_unsized_dataset(In& in, std::int32_t type, Version v, ModelDef& m) {
    auto rigid = [&](In& s) { return read_rigid_description(s, v); };
    switch (type) {
        case 0: {
            m.marker_sets.push_back(in.cstr("marker set name"));
            const auto k = in.count("marker names", 1);
            for (std::int32_t j = 0; j < k; ++j) in.cstr("marker name");
            break;
        }
        case 1: m.rigid_bodies.push_back(rigid(in)); break;
        case 2: {
            in.cstr("skeleton name");
            in.get<std::int32_t>("skeleton id");
            const auto k = in.count("skeleton bodies", 20);
            for (std::int32_t j = 0; j < k; ++j) rigid(in);
            ++m.skipped;
            break;
        }
        case 3: {  // force plate
            in.get<std::int32_t>("force plate id");
            in.cstr("force plate serial");
            in.skip(4 + 4 + 12 + 12 * 12 * 4 + 4 * 3 * 4 + 4 + 4, "force plate geometry");
            const auto k = in.count("force plate channels", 1);
            for (std::int32_t j = 0; j < k; ++j) in.cstr("channel name");
            ++m.skipped;
            break;
        }
        case 4: {  // device
            in.get<std::int32_t>("device id");
            in.cstr("device name");
            in.cstr("device serial");
            in.skip(8, "device type");
            const auto k = in.count("device channels", 1);
            for (std::int32_t j = 0; j < k; ++j) in.cstr("channel name");
            ++m.skipped;
            break;
        }
        case 5:
            in.cstr("camera name");
            in.skip(28, "camera pose");
            ++m.skipped;
            break;
        default: in.fail(log::cat("dataset type ", type, " cannot be skipped without its size (NatNet < 4.1)"));
    }
}

}  // namespace

ModelDef parse_modeldef(std::span<const std::uint8_t> data, Version v) {
    In in(data);
    ModelDef m;
    const auto n = in.count("datasets", 4);
    for (std::int32_t i = 0; i < n; ++i) {
        const auto type = in.get<std::int32_t>("dataset type");
        if (v.at_least(4, 1)) {
            const auto size = in.get<std::int32_t>("dataset size");
            if (size < 0 || static_cast<std::size_t>(size) > in.remaining())
                in.fail("dataset size runs past the packet");
            In s(data.subspan(in.pos(), static_cast<std::size_t>(size)));
            if (type == 1) m.rigid_bodies.push_back(read_rigid_description(s, v));
            else if (type == 0) m.marker_sets.push_back(s.cstr("marker set name"));
            else ++m.skipped;
            in.skip(static_cast<std::size_t>(size), "dataset");
            continue;
        }
        read_unsized_dataset(in, type, v, m);
    }
    return m;
}

ServerInfo parse_server_info(std::span<const std::uint8_t> data) {
    In in(data);
    ServerInfo s;
    if (data.size() < 256 + 8) in.fail("server info shorter than its name and versions");
    const auto* name = reinterpret_cast<const char*>(data.data());
    s.app_name.assign(name, strnlen(name, 256));
    in.skip(256, "server name");
    for (auto& x : s.app_version) x = in.get<std::uint8_t>("app version");
    s.natnet.major = in.get<std::uint8_t>("NatNet version");
    s.natnet.minor = in.get<std::uint8_t>("NatNet version");
    in.skip(2, "NatNet version");
    if (s.natnet.at_least(3, 0) && in.remaining() >= 15) {
        s.clock_frequency = in.get<std::uint64_t>("clock frequency");
        s.data_port = in.get<std::uint16_t>("data port");
        s.multicast = in.get<std::uint8_t>("multicast flag") != 0;
        for (auto& x : s.multicast_group) x = in.get<std::uint8_t>("multicast group");
    }
    return s;
}

namespace {
std::vector<std::uint8_t> packet(MessageId id, const std::vector<std::uint8_t>& body) {
    Out o;
    o.put(static_cast<std::uint16_t>(id));
    o.put(static_cast<std::uint16_t>(body.size()));
    o.b.insert(o.b.end(), body.begin(), body.end());
    return o.b;
}

// The sections after the rigid bodies that the bridge skips: skeletons, assets (4.1+), labeled
// markers, force plates and devices; empty, or one of each (`other`) to prove they are skipped.
void write_other_sections(Out& o, bool sized, bool other) {
    // Skeletons: one with one bone.
    o.put<std::int32_t>(other ? 1 : 0);
    std::size_t mark = sized ? o.reserve_size() : 0;
    if (other) {
        o.put<std::int32_t>(7);
        o.put<std::int32_t>(1);
        write_body(o, RigidBody{(7 << 16) | 1, {1, 2, 3}, {0, 0, 0, 1}, 0.001f, true});
    }
    if (sized) o.fill_size(mark);
    if (sized) {  // assets: one with one body and one marker
        o.put<std::int32_t>(other ? 1 : 0);
        mark = o.reserve_size();
        if (other) {
            o.put<std::int32_t>(42);
            o.put<std::int32_t>(1);
            write_body(o, RigidBody{43, {0, 0, 0}, {0, 0, 0, 1}, 0, true});
            o.put<std::int32_t>(1);
            o.put<std::int32_t>(44);
            for (int k = 0; k < 4; ++k) o.put<float>(0.5f);
            o.put<std::int16_t>(0);
            o.put<float>(0.0002f);
        }
        o.fill_size(mark);
    }
    // Labeled markers: three.
    o.put<std::int32_t>(other ? 3 : 0);
    mark = sized ? o.reserve_size() : 0;
    for (int k = 0; other && k < 3; ++k) {
        o.put<std::int32_t>(k);
        for (int j = 0; j < 4; ++j) o.put<float>(static_cast<float>(k + j));
        o.put<std::int16_t>(0x04);
        o.put<float>(0.0003f);
    }
    if (sized) o.fill_size(mark);
    // Force plates and devices: one each, two channels of one sample.
    for (int section = 0; section < 2; ++section) {
        o.put<std::int32_t>(other ? 1 : 0);
        mark = sized ? o.reserve_size() : 0;
        if (other) {
            o.put<std::int32_t>(section + 1);
            o.put<std::int32_t>(2);
            for (int c = 0; c < 2; ++c) {
                o.put<std::int32_t>(1);
                o.put<float>(9.81f);
            }
        }
        if (sized) o.fill_size(mark);
    }
}
}  // namespace

std::vector<std::uint8_t> build_frame(const FrameOfData& f, Version v, bool other) {
    const bool sized = v.at_least(4, 1);
    Out o;
    o.put(f.frame_number);
    // Marker sets: one set of two markers.
    o.put<std::int32_t>(other ? 1 : 0);
    std::size_t mark = sized ? o.reserve_size() : 0;
    if (other) {
        o.cstr("all");
        o.put<std::int32_t>(2);
        for (int k = 0; k < 6; ++k) o.put<float>(0.1f * static_cast<float>(k));
    }
    if (sized) o.fill_size(mark);
    o.put<std::int32_t>(0);  // legacy unlabeled markers
    if (sized) o.fill_size(o.reserve_size());
    o.put(static_cast<std::int32_t>(f.bodies.size()));
    mark = sized ? o.reserve_size() : 0;
    for (const auto& b : f.bodies) write_body(o, b);
    if (sized) o.fill_size(mark);
    write_other_sections(o, sized, other);
    o.put(f.timecode);
    o.put(f.timecode_sub);
    o.put(f.timestamp_s);
    o.put(f.mid_exposure);
    o.put(f.data_received);
    o.put(f.transmit);
    if (sized) {
        o.put(f.precision_s);
        o.put(f.precision_frac);
    }
    o.put(f.params);
    o.put<std::int32_t>(0);  // end of data
    return packet(kFrameOfData, o.b);
}

std::vector<std::uint8_t> build_modeldef(const ModelDef& m, Version v) {
    const bool sized = v.at_least(4, 1);
    Out o;
    o.put(static_cast<std::int32_t>(m.marker_sets.size() + m.rigid_bodies.size()));
    for (const auto& name : m.marker_sets) {
        o.put<std::int32_t>(0);
        const std::size_t mark = sized ? o.reserve_size() : 0;
        o.cstr(name);
        o.put<std::int32_t>(1);
        o.cstr(name + "_1");
        if (sized) o.fill_size(mark);
    }
    for (const auto& d : m.rigid_bodies) {
        o.put<std::int32_t>(1);
        const std::size_t mark = sized ? o.reserve_size() : 0;
        o.cstr(d.name);
        o.put(d.id);
        o.put(d.parent);
        for (float x : d.offset) o.put(x);
        if (v.at_least(4, 2))
            for (int k = 0; k < 4; ++k) o.put<float>(k == 3 ? 1.f : 0.f);
        o.put(static_cast<std::int32_t>(d.markers.size()));
        for (const auto& p : d.markers)
            for (float x : p) o.put(x);
        for (std::size_t k = 0; k < d.markers.size(); ++k) o.put(static_cast<std::int32_t>(k));
        if (v.at_least(4, 0))
            for (std::size_t k = 0; k < d.markers.size(); ++k) o.cstr(d.name + "_m" + std::to_string(k));
        if (sized) o.fill_size(mark);
    }
    return packet(kModelDef, o.b);
}

std::vector<std::uint8_t> build_server_info(const ServerInfo& s) {
    Out o;
    std::array<char, 256> name{};
    std::memcpy(name.data(), s.app_name.data(), std::min<std::size_t>(s.app_name.size(), 255));
    o.b.insert(o.b.end(), name.begin(), name.end());
    for (auto x : s.app_version) o.put(x);
    o.put(static_cast<std::uint8_t>(s.natnet.major));
    o.put(static_cast<std::uint8_t>(s.natnet.minor));
    o.put<std::uint8_t>(0);
    o.put<std::uint8_t>(0);
    o.put(s.clock_frequency);
    o.put(s.data_port);
    o.put(static_cast<std::uint8_t>(s.multicast ? 1 : 0));
    for (auto x : s.multicast_group) o.put(x);
    return packet(kServerInfo, o.b);
}

std::vector<std::uint8_t> build_simple(MessageId id, std::span<const std::uint8_t> body) {
    return packet(id, std::vector<std::uint8_t>(body.begin(), body.end()));
}

std::vector<std::uint8_t> build_connect() {
    // sSender (264 bytes: name, app version, NatNet version; zeros are fine) + connection options
    // (subscribed-data-only flag, bitstream version 0.0.0.0 = the server's own).
    std::vector<std::uint8_t> body(264 + 5, 0);
    std::memcpy(body.data(), "dw-mocap-bridge", 15);
    return packet(kConnect, body);
}

}  // namespace dw::natnet
