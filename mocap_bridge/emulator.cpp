#include "mocap_bridge/emulator.hpp"

#include <cmath>
#include <random>

#include "core/log.hpp"

namespace dw::natnet {

std::array<float, 3> ned_to_motive(const std::array<double, 3>& n) {
    return {static_cast<float>(n[0]), static_cast<float>(-n[2]), static_cast<float>(n[1])};
}

namespace {
constexpr std::int32_t kFirstInventedId = 100000;  // Hostility::new_ids_per_frame: ids from here on, never reused

BodyPose default_motion(int body, double t) {
    BodyPose p;
    if (body == 0) {
        p.ned = {0, 0, -1.4};
        return p;
    }
    const double phase = 2.0 * M_PI * body / 3.0;
    const double w = 0.5;  // rad/s: 0.5 m/s on a 1 m circle
    p.ned = {std::cos(w * t + phase), std::sin(w * t + phase), -1.4 - 0.3 - 0.5 * (body - 1)};
    return p;
}

// q (w, x, y, z) about NED axes -> the same rotation about Motive's axes (x, y, z, w on the wire).
std::array<float, 4> q_to_motive(const std::array<double, 4>& q) {
    // Motive axes: x = n, y = -d, z = e; a rotation's vector part maps like a position.
    return {static_cast<float>(q[1]), static_cast<float>(-q[3]), static_cast<float>(q[2]), static_cast<float>(q[0])};
}
}  // namespace

NatNetEmulator::NatNetEmulator(const EmulatorOptions& options) : options_(options), socket_(options.ip, options.port) {
    if (!options_.motion) options_.motion = default_motion;
    start_ns_ = SystemClock::instance().monotonic_ns();
    thread_ = std::thread([this] { loop(); });
}

NatNetEmulator::~NatNetEmulator() { stop(); }

void NatNetEmulator::stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
}

std::size_t NatNetEmulator::clients() const {
    std::lock_guard lock(mutex_);
    return clients_.size();
}

void NatNetEmulator::handle(const std::vector<std::uint8_t>& packet, const Endpoint& from) {
    std::uint16_t id = 0;
    try {
        id = message_id(packet);
    } catch (const std::exception&) {
        return;
    }
    if (id == kConnect) {
        {
            std::lock_guard lock(mutex_);
            if (std::find(clients_.begin(), clients_.end(), from) == clients_.end()) clients_.push_back(from);
        }
        ServerInfo s;
        s.app_name = "dw-natnet-emulator";
        s.app_version = {3, 1, 0, 0};
        s.natnet = options_.version;
        s.clock_frequency = options_.clock_frequency;
        s.data_port = static_cast<std::uint16_t>(options_.port + 1);
        socket_.send_to(from, build_server_info(s));
    } else if (id == kRequestModelDef) {
        ModelDef m;
        m.marker_sets = {"all"};
        for (std::size_t i = 0; i < options_.names.size(); ++i) {
            RigidBodyDescription d;
            d.name = options_.names[i];
            d.id = static_cast<std::int32_t>(i + 1);
            d.markers = {{0.05f, 0, 0}, {-0.05f, 0, 0}, {0, 0, 0.05f}};
            m.rigid_bodies.push_back(d);
        }
        socket_.send_to(from, build_modeldef(m, options_.version));
    } else if (id == kDisconnect) {
        std::lock_guard lock(mutex_);
        clients_.erase(std::remove(clients_.begin(), clients_.end(), from), clients_.end());
    }
    // KEEPALIVE needs no answer.
}

std::vector<std::uint8_t> NatNetEmulator::frame(std::int32_t number, double t) {
    FrameOfData f;
    f.frame_number = number;
    for (std::size_t i = 0; i < options_.names.size(); ++i) {
        // The pose at mid-exposure, the instant the frame's timing says it was captured.
        const BodyPose p = options_.motion(static_cast<int>(i), t - options_.latency_s);
        RigidBody b;
        b.id = static_cast<std::int32_t>(i + 1);
        b.tracking_valid = true;
        for (const auto& l : options_.losses) {
            if (l.body == static_cast<int>(i) && t >= l.start_s && t < l.start_s + l.duration_s)
                b.tracking_valid = false;
        }
        if (b.tracking_valid) {
            b.position = ned_to_motive(p.ned);
            b.orientation = q_to_motive(p.q_ned);
            b.mean_error = 0.0002f;
        }  // a lost body: zeros, as Motive sends
        f.bodies.push_back(b);
    }
    for (int k = 0; k < options_.hostile.new_ids_per_frame; ++k) {
        RigidBody b;
        b.id = kFirstInventedId + number * options_.hostile.new_ids_per_frame + k;
        b.tracking_valid = true;
        b.position = {0.1f, 1.0f, 0.2f};
        b.orientation = {0, 0, 0, 1};
        f.bodies.push_back(b);
    }
    const Nanos now = SystemClock::instance().monotonic_ns();
    const auto ticks = static_cast<std::uint64_t>(to_seconds(now) * static_cast<double>(options_.clock_frequency));
    f.transmit = ticks;
    f.mid_exposure =
        ticks - static_cast<std::uint64_t>(options_.latency_s * static_cast<double>(options_.clock_frequency));
    f.data_received = f.mid_exposure + options_.clock_frequency / 500;
    f.timestamp_s = options_.hostile.frozen_clock ? 0.0 : t;
    return build_frame(f, options_.version, options_.other_sections);
}

std::vector<std::uint8_t> NatNetEmulator::hostile_packet(std::int32_t number, double t, std::mt19937_64& rng) {
    auto packet = frame(number, t);
    switch ((number / kHostileEvery) % 3) {
        case 0:  // cut short, anywhere after the message id
            packet.resize(2 + rng() % (packet.size() - 2));
            return packet;
        case 1: {  // oversized: the largest UDP datagram, the frame's counts and sizes garbage
            packet.resize(kMaxDatagramBytes);
            for (std::size_t i = 8; i < packet.size(); ++i) packet[i] = static_cast<std::uint8_t>(rng());
            return packet;
        }
        default: {  // the named bodies tracked at an absurd place, at an absurd time
            constexpr std::array<float, 5> kAbsurd = {NAN, INFINITY, -INFINITY, 3.4e38f, -3.4e38f};
            const float v = kAbsurd[static_cast<std::size_t>(number / kHostileEvery / 3) % kAbsurd.size()];
            FrameOfData f;
            f.frame_number = number;
            for (std::size_t i = 0; i < options_.names.size(); ++i)
                f.bodies.push_back({static_cast<std::int32_t>(i + 1), {v, v, v}, {v, v, v, v}, v, true});
            f.timestamp_s = v;
            return build_frame(f, options_.version, options_.other_sections);
        }
    }
}

void NatNetEmulator::loop() {
    std::mt19937_64 rng(options_.seed);
    std::uniform_real_distribution<double> u(0, 1);
    const double period_ns = static_cast<double>(kNanosPerSecond) / options_.rate_hz;
    std::int32_t number = 0;
    Nanos next = start_ns_;
    while (!stop_) {
        const Nanos now = SystemClock::instance().monotonic_ns();
        const int wait_ms = static_cast<int>(std::max<Nanos>(0, (next - now) / 1'000'000));
        Endpoint from;
        if (auto p = socket_.receive(std::min(wait_ms, 5), &from)) {
            handle(*p, from);
            continue;
        }
        const Nanos left = next - SystemClock::instance().monotonic_ns();
        if (left > 1'000'000) continue;                           // keep listening until the last millisecond
        while (SystemClock::instance().monotonic_ns() < next) {}  // then spin, for an even rate
        const double t = to_seconds(next - start_ns_);
        next += static_cast<Nanos>(period_ns);
        ++number;
        if (options_.drop_probability > 0 && u(rng) < options_.drop_probability) continue;
        const auto packet = frame(number, t);
        std::vector<Endpoint> to;
        {
            std::lock_guard lock(mutex_);
            to = clients_;
        }
        for (const auto& c : to) socket_.send_to(c, packet);
        if (!to.empty()) ++sent_;
        if (!options_.hostile.packets || number % kHostileEvery != 0) continue;
        const auto hostile = hostile_packet(number, t, rng);
        for (const auto& c : to) socket_.send_to(c, hostile);
    }
}

}  // namespace dw::natnet
