// NatNet: byte-exact packets of the 3.0, 3.1, 4.0 and 4.1 bitstreams written by hand from the
// published layout (../shared/SPECS.md §2), model definitions, a seeded fuzz loop, and the
// emulator -> client -> converter path on loopback (tracking loss, dropped frames, axes).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <thread>

#include "core/errors.hpp"
#include "mocap_bridge/bridge.hpp"
#include "mocap_bridge/emulator.hpp"
#include "mocap_bridge/natnet.hpp"

using namespace dw::natnet;
using namespace std::chrono_literals;

namespace {
// A little-endian byte writer, separate from the library's, to state the layout independently.
struct Bytes {
    std::vector<std::uint8_t> b;
    template <class T>
    Bytes& put(T v) {
        const auto* p = reinterpret_cast<const std::uint8_t*>(&v);
        b.insert(b.end(), p, p + sizeof(T));
        return *this;
    }
    Bytes& i32(std::int32_t v) { return put(v); }
    Bytes& f32(float v) { return put(v); }
    Bytes& str(const char* s) {
        b.insert(b.end(), s, s + std::strlen(s) + 1);
        return *this;
    }
    std::size_t mark() {
        i32(0);
        return b.size();
    }  // a 4.1 section size, filled by size_from()
    void size_from(std::size_t m) {
        const auto n = static_cast<std::int32_t>(b.size() - m);
        std::memcpy(b.data() + m - 4, &n, 4);
    }
};

// FRAMEOFDATA payload: frame 1234, one marker set "m" (1 marker), no legacy markers, two rigid
// bodies (ids 1 and 2; the second not tracked), one skeleton (one bone), one asset (4.1 only), one
// labeled marker, one force plate (2 channels x 1 sample), no devices, then the suffix.
std::vector<std::uint8_t> hand_frame(Version v) {
    const bool sized = v.at_least(4, 1);
    Bytes p;
    p.i32(1234);                             // frameNumber
    p.i32(1);                                // marker sets: count
    std::size_t m = sized ? p.mark() : 0;    //   [4.1: bytes of the section]
    p.str("m").i32(1).f32(1).f32(2).f32(3);  //   name, nMarkers, xyz
    if (sized) p.size_from(m);
    p.i32(0);  // legacy unlabeled markers: none
    if (sized) p.size_from(p.mark());
    p.i32(2);  // rigid bodies: count
    m = sized ? p.mark() : 0;
    p.i32(1)
        .f32(0.5f)
        .f32(1.5f)
        .f32(-0.25f)  //   id, x, y, z
        .f32(0)
        .f32(0)
        .f32(0.38268343f)
        .f32(0.92387953f)  //   qx, qy, qz, qw
        .f32(0.0004f)
        .put<std::int16_t>(1);  //   meanError, params (bit 0: tracked)
    p.i32(2).f32(0).f32(0).f32(0).f32(0).f32(0).f32(0).f32(1).f32(0).put<std::int16_t>(0);  // lost
    if (sized) p.size_from(m);
    p.i32(1);  // skeletons: count
    m = sized ? p.mark() : 0;
    p.i32(9).i32(1);  //   skeleton id, nBones
    p.i32((9 << 16) | 1).f32(1).f32(1).f32(1).f32(0).f32(0).f32(0).f32(1).f32(0).put<std::int16_t>(1);
    if (sized) p.size_from(m);
    if (sized) {  // assets (4.1+): count, size
        p.i32(1);
        m = p.mark();
        p.i32(77).i32(1);  //   asset id, nRigidBodies
        p.i32(78).f32(0).f32(0).f32(0).f32(0).f32(0).f32(0).f32(1).f32(0).put<std::int16_t>(1);
        p.i32(1).i32(79).f32(1).f32(2).f32(3).f32(0.01f).put<std::int16_t>(0).f32(0.0001f);  // nMarkers, marker
        p.size_from(m);
    }
    p.i32(1);  // labeled markers: count
    m = sized ? p.mark() : 0;
    p.i32(5).f32(1).f32(2).f32(3).f32(0.014f).put<std::int16_t>(0x04).f32(0.0002f);  // id xyz size params residual
    if (sized) p.size_from(m);
    p.i32(1);  // force plates: count
    m = sized ? p.mark() : 0;
    p.i32(1).i32(2).i32(1).f32(10).i32(1).f32(20);  //   id, nChannels, (nFrames, values)...
    if (sized) p.size_from(m);
    p.i32(0);  // devices: none
    if (sized) p.size_from(p.mark());
    p.put<std::uint32_t>(0x01020304).put<std::uint32_t>(7);                        // timecode, timecodeSub
    p.put<double>(12.5);                                                           // timestamp [s]
    p.put<std::uint64_t>(1000).put<std::uint64_t>(1100).put<std::uint64_t>(1200);  // mid-exposure, received, transmit
    if (sized) p.put<std::uint32_t>(1700000000).put<std::uint32_t>(42);            // precision timestamp
    p.put<std::int16_t>(0x01);                                                     // params: recording
    p.i32(0);                                                                      // end of data
    return p.b;
}
}  // namespace

TEST(NatNet, ParsesByteExactFramesOfEveryVersion) {
    for (Version v : {Version{3, 0}, Version{3, 1}, Version{4, 0}, Version{4, 1}}) {
        SCOPED_TRACE(std::to_string(v.major) + "." + std::to_string(v.minor));
        const auto bytes = hand_frame(v);
        const FrameOfData f = parse_frame(bytes, v);
        EXPECT_EQ(f.frame_number, 1234);
        ASSERT_EQ(f.bodies.size(), 2u);  // skeleton bones and asset bodies are not top-level bodies
        EXPECT_EQ(f.bodies[0].id, 1);
        EXPECT_FLOAT_EQ(f.bodies[0].position[0], 0.5f);
        EXPECT_FLOAT_EQ(f.bodies[0].position[1], 1.5f);
        EXPECT_FLOAT_EQ(f.bodies[0].position[2], -0.25f);
        EXPECT_FLOAT_EQ(f.bodies[0].orientation[2], 0.38268343f);
        EXPECT_FLOAT_EQ(f.bodies[0].orientation[3], 0.92387953f);
        EXPECT_FLOAT_EQ(f.bodies[0].mean_error, 0.0004f);
        EXPECT_TRUE(f.bodies[0].tracking_valid);
        EXPECT_FALSE(f.bodies[1].tracking_valid);
        EXPECT_EQ(f.timecode, 0x01020304u);
        EXPECT_EQ(f.timecode_sub, 7u);
        EXPECT_DOUBLE_EQ(f.timestamp_s, 12.5);
        EXPECT_EQ(f.mid_exposure, 1000u);
        EXPECT_EQ(f.data_received, 1100u);
        EXPECT_EQ(f.transmit, 1200u);
        EXPECT_EQ(f.precision_s, v.at_least(4, 1) ? 1700000000u : 0u);
        EXPECT_EQ(f.params, 1);
        // One byte short anywhere in the suffix is a clear error, not a read past the end.
        auto cut = bytes;
        cut.pop_back();
        EXPECT_THROW(parse_frame(cut, v), dw::InputError);
    }
    // A 4.1 frame read as 3.1 (or the reverse) does not pass silently.
    EXPECT_THROW(parse_frame(hand_frame({4, 1}), {3, 1}), dw::InputError);
}

TEST(NatNet, ParsesByteExactModelDefinitions) {
    for (Version v : {Version{3, 0}, Version{4, 0}, Version{4, 1}}) {
        SCOPED_TRACE(std::to_string(v.major) + "." + std::to_string(v.minor));
        const bool sized = v.at_least(4, 1);
        Bytes p;
        p.i32(3);  // datasets
        p.i32(0);  // marker set
        std::size_t m = sized ? p.mark() : 0;
        p.str("all").i32(2).str("a1").str("a2");
        if (sized) p.size_from(m);
        p.i32(1);  // rigid body
        m = sized ? p.mark() : 0;
        p.str("v1").i32(3).i32(-1).f32(0).f32(0.01f).f32(0);          // name, id, parent, offset
        p.i32(2).f32(0.05f).f32(0).f32(0).f32(-0.05f).f32(0).f32(0);  // markers
        p.i32(0).i32(0);                                              // active labels
        if (v.at_least(4, 0)) p.str("v1_a").str("v1_b");              // marker names (4.0+)
        if (sized) p.size_from(m);
        p.i32(5);  // camera
        m = sized ? p.mark() : 0;
        p.str("cam1").f32(1).f32(2).f32(3).f32(0).f32(0).f32(0).f32(1);
        if (sized) p.size_from(m);
        const ModelDef d = parse_modeldef(p.b, v);
        ASSERT_EQ(d.rigid_bodies.size(), 1u);
        EXPECT_EQ(d.rigid_bodies[0].name, "v1");
        EXPECT_EQ(d.rigid_bodies[0].id, 3);
        EXPECT_EQ(d.rigid_bodies[0].markers.size(), 2u);
        EXPECT_EQ(d.rigid_bodies[0].marker_names.size(), v.at_least(4, 0) ? 2u : 0u);
        EXPECT_EQ(d.marker_sets, std::vector<std::string>{"all"});
        EXPECT_EQ(d.skipped, 1);
    }
}

TEST(NatNet, BuilderAndParserAgree) {
    for (Version v : {Version{3, 0}, Version{3, 1}, Version{4, 0}, Version{4, 1}}) {
        FrameOfData f;
        f.frame_number = 99;
        f.bodies = {RigidBody{4, {1, 2, 3}, {0, 0, 0, 1}, 0.001f, true}, RigidBody{5, {}, {0, 0, 0, 1}, 0, false}};
        f.mid_exposure = 10;
        f.transmit = 30;
        const auto packet = build_frame(f, v);
        ASSERT_EQ(message_id(packet), kFrameOfData);
        const FrameOfData g = parse_frame(payload(packet), v);
        EXPECT_EQ(g.frame_number, 99);
        ASSERT_EQ(g.bodies.size(), 2u);
        EXPECT_EQ(g.bodies[0].position, f.bodies[0].position);
        EXPECT_EQ(g.transmit, 30u);
        ServerInfo s;
        s.natnet = v;
        s.clock_frequency = 1234567;
        EXPECT_EQ(parse_server_info(payload(build_server_info(s))).clock_frequency, 1234567u);
    }
}

TEST(NatNet, MalformedTruncatedAndOversizedPacketsNeverCrash) {
    std::mt19937_64 rng(1511);
    int errors = 0;
    for (int trial = 0; trial < 8000; ++trial) {
        const Version v = std::array<Version, 4>{Version{3, 0}, Version{3, 1}, Version{4, 0}, Version{4, 1}}[trial % 4];
        auto bytes = hand_frame(v);
        switch (rng() % 4) {
            case 0: bytes.resize(rng() % bytes.size()); break;
            case 1:
                for (int k = 0; k < 4; ++k) bytes[rng() % bytes.size()] ^= static_cast<std::uint8_t>(1 + rng() % 255);
                break;
            case 2: {  // an oversized count or size where a count lives
                const std::size_t at = 4 * (rng() % (bytes.size() / 4));
                const std::int32_t huge = static_cast<std::int32_t>(rng() % 2 ? 0x7FFFFFFF : 0x80000000u);
                std::memcpy(bytes.data() + at, &huge, 4);
                break;
            }
            default:
                bytes.insert(bytes.begin() + static_cast<std::ptrdiff_t>(rng() % bytes.size()),
                             static_cast<std::uint8_t>(rng()));
                break;
        }
        try {
            parse_frame(bytes, v);
        } catch (const dw::InputError& e) {
            ++errors;
            EXPECT_EQ(std::string(e.what()).rfind("NatNet packet byte ", 0), 0u) << e.what();
        }
        try {
            parse_modeldef(bytes, v);
        } catch (const dw::InputError&) {}
    }
    EXPECT_GT(errors, 4000);
}

TEST(Bridge, AxisMapsAreCheckedAndConvertToNed) {
    EXPECT_EQ(AxisMap::parse("x,z,-y").det(), 1);
    EXPECT_EQ(AxisMap::parse("x,y,z").det(), 1);
    EXPECT_EQ(AxisMap::parse("x,z,y").det(), -1);
    EXPECT_THROW(AxisMap::parse("x,x,y"), dw::InputError);
    EXPECT_THROW(AxisMap::parse("x,z"), dw::InputError);
    EXPECT_THROW(AxisMap::parse("x,z,-y,w"), dw::InputError);
}

TEST(Bridge, EmulatorToNedWithHonestTimestampsAndDroppedFrames) {
    EmulatorOptions eo;
    eo.port = 0;
    eo.drop_probability = 0.1;
    NatNetEmulator emulator(eo);
    ClientOptions co;
    co.command_port = emulator.port();
    NatNetClient client(co);
    const ServerInfo server = client.connect();
    EXPECT_EQ(server.natnet.major, 4);
    EXPECT_EQ(server.natnet.minor, 1);
    const ModelDef models = client.request_modeldef();
    ASSERT_EQ(models.rigid_bodies.size(), 4u);
    BridgeOptions bo;
    bo.names["v1"] = "leader";
    FrameConverter conv(bo, server, models);
    int frames = 0;
    std::int32_t first = -1, last = -1;
    while (frames < 200) {
        auto r = client.next_frame(1000);
        ASSERT_TRUE(r.has_value());
        if (first < 0) first = r->frame.frame_number;
        last = r->frame.frame_number;
        const auto out = conv.convert(r->frame, r->receive_wall_ns);
        ++frames;
        ASSERT_EQ(out.frame.bodies().size(), 4u);
        EXPECT_EQ(out.frame.bodies()[0].name(), "sufferer");
        EXPECT_EQ(out.frame.bodies()[1].name(), "leader");
        EXPECT_NEAR(out.frame.bodies()[0].position_m().z(), -1.4, 1e-6);  // NED: the stand is 1.4 m up
        // The circle of the default motion, in NED: radius 1 m, heights below the sufferer.
        const auto& v2 = out.frame.bodies()[2].position_m();
        EXPECT_NEAR(std::hypot(v2.x(), v2.y()), 1.0, 1e-5);
        EXPECT_NEAR(v2.z(), -2.2, 1e-5);
        // Compensated: the receive time minus the 4 ms between mid-exposure and transmit.
        const double stamp =
            static_cast<double>(out.frame.header().stamp().sec()) + out.frame.header().stamp().nanosec() * 1e-9;
        EXPECT_NEAR(static_cast<double>(r->receive_wall_ns) * 1e-9 - stamp, 0.004, 1e-5);
    }
    EXPECT_EQ(conv.dropped(), static_cast<std::uint64_t>(last - first + 1 - frames));
    EXPECT_GT(conv.dropped(), 5u);
}

// request_modeldef asks again when an answer is slow (a busy server), so a second answer may come
// after the first: next_frame waits past it for the frame (found under the sanitizer, eight test
// processes on two cores). A server written here answers the model definitions twice, then streams.
TEST(Bridge, ALateSecondAnswerToModelDefinitionsIsNotTheEndOfTheWaitForAFrame) {
    UdpSocket server("127.0.0.1", 0);
    std::thread serve([&server] {
        Endpoint client;
        ServerInfo info;
        info.natnet = {4, 1};
        for (int got = 0; got < 2;) {
            const auto p = server.receive(5000, &client);
            if (!p) return;
            if (message_id(*p) == kConnect) server.send_to(client, build_server_info(info)), ++got;
            if (message_id(*p) == kRequestModelDef) {
                ModelDef m;
                m.rigid_bodies.push_back({"v1", 1, -1, {}, {}, {}});
                for (int answer = 0; answer < 2; ++answer) server.send_to(client, build_modeldef(m, info.natnet));
                ++got;
            }
        }
        FrameOfData f;
        f.frame_number = 7;
        f.bodies.push_back({1, {0.1f, 1.0f, 0.2f}, {0, 0, 0, 1}, 0, true});
        server.send_to(client, build_frame(f, info.natnet));
    });
    ClientOptions co;
    co.command_port = server.port();
    NatNetClient client(co);
    client.connect();
    EXPECT_EQ(client.request_modeldef().rigid_bodies.size(), 1u);
    const auto r = client.next_frame(5000);
    serve.join();
    ASSERT_TRUE(r.has_value()) << "the second model definitions ended the wait";
    EXPECT_EQ(r->frame.frame_number, 7);
}

TEST(Bridge, TrackingLossIsFlaggedWithinOneFrameAndVelocityIsSaneRightAfter) {
    EmulatorOptions eo;
    eo.port = 0;
    eo.losses = {{2, 1.0, 0.5}};  // body 2 (v2) loses tracking for 0.5 s after 1 s
    NatNetEmulator emulator(eo);
    ClientOptions co;
    co.command_port = emulator.port();
    NatNetClient client(co);
    const ServerInfo server = client.connect();
    const ModelDef models = client.request_modeldef();
    FrameConverter conv({}, server, models);
    bool lost_seen = false, back = false;
    int frames_after = 0, lost_frames = 0;
    while (frames_after < 20) {
        auto r = client.next_frame(1000);
        ASSERT_TRUE(r.has_value());
        const auto out = conv.convert(r->frame, r->receive_wall_ns);
        const bool valid_on_wire = r->frame.bodies[2].tracking_valid;
        // Flagged in the very frame that says so.
        EXPECT_EQ(out.frame.bodies()[2].tracking_valid(), valid_on_wire);
        EXPECT_EQ(out.states[2].tracking_valid(), valid_on_wire);
        if (!valid_on_wire) {
            lost_seen = true;
            ++lost_frames;
            EXPECT_GE(out.states[2].staleness_s(), 0.0);
        } else if (lost_seen) {
            back = true;
        }
        if (back) {
            ++frames_after;
            if (frames_after >= 2) {  // one frame to restart the estimator, then the true velocity
                const double speed = std::hypot(out.states[2].velocity_mps().x(), out.states[2].velocity_mps().y());
                EXPECT_NEAR(speed, 0.5, 0.05) << "frame " << frames_after << " after tracking returned";
                EXPECT_NEAR(out.states[2].velocity_mps().z(), 0.0, 0.05);
            }
        }
    }
    EXPECT_NEAR(lost_frames, 90, 3);  // 0.5 s at 180 Hz
}

// Issue 70: a Motive that sends new rigid-body ids every frame grew the bridge by 608 MB in 25 s,
// and one whose clock stood still by 228 MB: each body's velocity samples were aged out by that
// clock only. The bridge now tracks at most flight::kMaxBodies bodies (the least recently seen
// forgotten) and keeps at most kMaxRecentSamples per body, while the bodies in use keep their
// velocity.
TEST(Bridge, NewIdsEveryFrameOrAFrozenClockHoldBoundedMemory) {
    ServerInfo server;
    server.clock_frequency = 1'000'000;
    ModelDef models;
    models.rigid_bodies.push_back({"v1", 1, -1, {}});
    FrameConverter conv({}, server, models);
    auto body = [](int id, float x) {
        RigidBody b;
        b.id = id;
        b.position = {x, 1.0f, 0.5f};
        b.orientation = {0, 0, 0, 1};
        b.tracking_valid = true;
        return b;
    };
    constexpr int kFrames = 4000, kNewPerFrame = 8;
    for (int n = 0; n < kFrames; ++n) {
        FrameOfData f;
        f.frame_number = n + 1;
        f.timestamp_s = n < kFrames / 2 ? n / 180.0 : kFrames / 360.0;  // then the clock stands still
        f.transmit = f.mid_exposure = static_cast<std::uint64_t>(1000 + n * 5556);
        f.bodies.push_back(body(1, 0.01f * static_cast<float>(n)));  // the one vehicle flying, every frame
        for (int k = 0; k < kNewPerFrame; ++k) f.bodies.push_back(body(1000 + n * kNewPerFrame + k, 0.5f));
        const auto out = conv.convert(f, 1'700'000'000'000'000'000 + static_cast<std::int64_t>(n) * 5'556'000);
        if (n == kFrames / 2 - 1) {
            EXPECT_NEAR(out.states.at(0).velocity_mps().x(), 1.8, 1e-3) << "the vehicle in use lost its velocity";
        }
    }
    // The invented ids are in the frames, but no model definition gave them: no vehicle state, no
    // track (before, each became an instance of vehicles/state: past DDS's 256 the writes failed).
    EXPECT_EQ(conv.undefined(), static_cast<std::uint64_t>(kFrames) * kNewPerFrame);
    const auto held = conv.held();
    EXPECT_LE(held.bodies, dw::flight::kMaxBodies);
    ASSERT_GT(held.bodies, 0u);
    // One sample per body seen once, and the vehicle's window, however long the clock stood still.
    EXPECT_LE(held.samples, held.bodies - 1 + kMaxRecentSamples);
}

// Issue 70: what Motive sends is checked before it enters the lab. A body at NaN or at ±3.4e38,
// or with a quaternion that does not normalise, is passed on as lost (no pose, no velocity) and
// counted; a frame whose clock is NaN is refused whole; the plausible bodies beside them pass.
TEST(Bridge, NonFiniteOrAbsurdBodiesNeverEnterTheLab) {
    ServerInfo server;
    server.clock_frequency = 1'000'000;
    ModelDef models;
    for (int id = 1; id <= 4; ++id) models.rigid_bodies.push_back({"v" + std::to_string(id), id, -1, {}});
    FrameConverter conv({}, server, models);
    auto body = [](int id, float x) {
        RigidBody b;
        b.id = id;
        b.position = {x, 1.0f, 0.5f};
        b.tracking_valid = true;
        return b;
    };
    for (int n = 0; n < 6; ++n) {
        FrameOfData f;
        f.frame_number = n + 1;
        f.timestamp_s = n / 180.0;
        f.transmit = f.mid_exposure = static_cast<std::uint64_t>(1000 + n * 5556);
        const float huge = n % 2 ? 3.4e38f : -3.4e38f;  // alternating, as a confused solver sends
        f.bodies = {body(1, 0.1f * static_cast<float>(n)), body(2, std::nanf("")), body(3, huge), body(4, 0.2f)};
        f.bodies[3].orientation = {0, 0, 0, 0};
        const auto out = conv.convert(f, 1'700'000'000'000'000'000 + n * 5'556'000);
        ASSERT_EQ(out.frame.bodies().size(), 4u);
        EXPECT_TRUE(out.frame.bodies()[0].tracking_valid());
        for (std::size_t k = 1; k < 4; ++k) {
            SCOPED_TRACE(k);
            EXPECT_FALSE(out.frame.bodies()[k].tracking_valid());
            EXPECT_FALSE(out.states[k].tracking_valid());
        }
        for (const auto& s : out.states)
            for (double v : {s.position_m().x(), s.position_m().y(), s.position_m().z(), s.velocity_mps().x(),
                             s.velocity_mps().y(), s.velocity_mps().z()})
                EXPECT_TRUE(std::isfinite(v));
        for (const auto& b : out.frame.bodies())
            for (double v : {b.position_m().x(), b.position_m().y(), b.position_m().z(), b.orientation().w()})
                EXPECT_TRUE(std::isfinite(v));
    }
    EXPECT_EQ(conv.implausible(), 18u);
    FrameOfData nan_clock;
    nan_clock.frame_number = 7;
    nan_clock.timestamp_s = std::nan("");
    nan_clock.bodies = {body(1, 0.5f)};
    bool refused = false;
    conv.convert(nan_clock, 1'700'000'000'100'000'000, &refused);
    EXPECT_TRUE(refused);
    EXPECT_EQ(conv.implausible(), 19u);
    // A clock that is finite but no Motive's (3.4e38 s, then -3.4e38 s) is refused too: before, the
    // second looked like Motive restarting, every estimator was reset, and a lost body's next state
    // had no pose at all (zeros: D = 0, the floor).
    for (const double absurd : {3.4e38, -3.4e38, -1.0}) {
        FrameOfData f;
        f.frame_number = 8;
        f.timestamp_s = absurd;
        f.bodies = {body(1, 0.5f)};
        refused = false;
        conv.convert(f, 1'700'000'000'100'000'000, &refused);
        EXPECT_TRUE(refused) << absurd;
    }
    FrameOfData lost;
    lost.frame_number = 9;
    lost.timestamp_s = 7 / 180.0;
    lost.bodies = {body(1, 0.5f)};
    lost.bodies[0].tracking_valid = false;
    const auto held = conv.convert(lost, 1'700'000'000'100'000'000);
    EXPECT_NEAR(held.states.at(0).position_m().x(), 0.5, 1e-6) << "body 1's last pose was forgotten";
    EXPECT_EQ(conv.implausible(), 22u);
}
