#include "mocap_bridge/bridge.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <optional>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/time.hpp"
#include "physics/vehicle.hpp"

namespace dw::natnet {

namespace {
constexpr Nanos kKeepAlivePeriod_ns = kNanosPerSecond;  // next_frame sends a keepalive about this often
}  // namespace

NatNetClient::NatNetClient(const ClientOptions& o)
    : options_(o), socket_(o.local_ip, 0), server_endpoint_(Endpoint::make(o.server_ip, o.command_port)) {}

ServerInfo NatNetClient::connect() {
    const Nanos deadline =
        SystemClock::instance().monotonic_ns() + static_cast<Nanos>(options_.connect_timeout_ms) * 1'000'000;
    while (SystemClock::instance().monotonic_ns() < deadline) {
        socket_.send_to(server_endpoint_, build_connect());
        for (int i = 0; i < 5; ++i) {
            auto p = socket_.receive(100);
            if (!p) continue;
            try {
                if (message_id(*p) == kServerInfo) {
                    server_ = parse_server_info(payload(*p));
                    last_keepalive_ = SystemClock::instance().monotonic_ns();
                    return server_;
                }
            } catch (const InputError&) {
                ++malformed_;
            }
        }
    }
    throw RuntimeError(log::cat("no NatNet server answered at ", server_endpoint_.str(), " within ",
                                options_.connect_timeout_ms, " ms (is Motive streaming, unicast, to this host?)"));
}

ModelDef NatNetClient::request_modeldef() {
    for (int attempt = 0; attempt < 10; ++attempt) {
        socket_.send_to(server_endpoint_, build_simple(kRequestModelDef));
        for (int i = 0; i < 20; ++i) {
            auto p = socket_.receive(50);
            if (!p) break;
            try {
                if (message_id(*p) == kModelDef) return parse_modeldef(payload(*p), server_.natnet);
            } catch (const InputError& e) {
                ++malformed_;
                log::warn("model definitions: ", e.what());
            }
        }
    }
    throw RuntimeError("the NatNet server sent no model definitions");
}

std::optional<NatNetClient::Received> NatNetClient::next_frame(int timeout_ms) {
    const auto& clock = SystemClock::instance();
    Nanos now = clock.monotonic_ns();
    const Nanos deadline = now + static_cast<Nanos>(timeout_ms) * 1'000'000;
    do {  // until a frame or the deadline: a packet of another kind is not the end of the wait
        if (now - last_keepalive_ > kKeepAlivePeriod_ns) {
            socket_.send_to(server_endpoint_, build_simple(kKeepAlive));
            last_keepalive_ = now;
        }
        auto p = socket_.receive(static_cast<int>(std::max<Nanos>(0, deadline - now) / 1'000'000));
        if (!p) return std::nullopt;
        const Nanos received = clock.now_ns();
        try {
            // Another kind: e.g. a second answer to model definitions asked again (request_modeldef
            // asks again when the first answer is slow), or a server's message string.
            if (message_id(*p) == kFrameOfData) return Received{parse_frame(payload(*p), server_.natnet), received};
        } catch (const InputError& e) {
            if (++malformed_ <= 5) log::warn("skipped a malformed NatNet packet: ", e.what());
        }
        now = clock.monotonic_ns();
    } while (now < deadline);
    return std::nullopt;
}

AxisMap AxisMap::parse(const std::string& text) {
    AxisMap m;
    std::array<bool, 3> used{};
    std::size_t start = 0;
    for (int i = 0; i < 3; ++i) {
        if (start > text.size())
            throw InputError(log::cat("--axes '", text, "': expected three axes, e.g. x,z,-y (N, E, D)"));
        const std::size_t comma = text.find(',', start);
        std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
        start = comma == std::string::npos ? text.size() + 1 : comma + 1;
        int sign = 1;
        if (!item.empty() && (item[0] == '-' || item[0] == '+')) {
            sign = item[0] == '-' ? -1 : 1;
            item = item.substr(1);
        }
        if (item.size() != 1 || item[0] < 'x' || item[0] > 'z' || used[static_cast<std::size_t>(item[0] - 'x')]) {
            throw InputError(
                log::cat("--axes '", text, "': expected three of x, y, z with signs, e.g. x,z,-y (N, E, D)"));
        }
        used[static_cast<std::size_t>(item[0] - 'x')] = true;
        m.source[static_cast<std::size_t>(i)] = item[0] - 'x';
        m.sign[static_cast<std::size_t>(i)] = sign;
    }
    if (start <= text.size()) throw InputError(log::cat("--axes '", text, "': more than three axes"));
    return m;
}

int AxisMap::det() const {
    // The sign of the permutation times the product of the signs.
    int inversions = 0;
    for (int i = 0; i < 3; ++i) {
        for (int j = i + 1; j < 3; ++j)
            inversions += source[static_cast<std::size_t>(i)] > source[static_cast<std::size_t>(j)];
    }
    return (inversions % 2 ? -1 : 1) * sign[0] * sign[1] * sign[2];
}

FrameConverter::FrameConverter(const BridgeOptions& o, const ServerInfo& server, const ModelDef& models)
    : options_(o), server_(server) {
    for (const auto& d : models.rigid_bodies) names_[d.id] = d.name;
}

double FrameConverter::camera_time_s(const FrameOfData& f, Nanos receive_wall_ns) {
    const double receive = to_seconds(receive_wall_ns);
    if (server_.clock_frequency == 0 || f.transmit == 0) return receive;  // no camera stamps (< 3.0)
    const double freq = static_cast<double>(server_.clock_frequency);
    switch (options_.mode) {
        case msg::MOCAP_STAMP_RECEIVE: return receive;
        case msg::MOCAP_STAMP_COMPENSATED: return receive - static_cast<double>(f.transmit - f.mid_exposure) / freq;
        case msg::MOCAP_STAMP_CLOCK_SYNC: {
            // The smallest (receive - transmit) seen so far: the clocks' offset plus the network's
            // least delay; mid-exposure is mapped through it.
            const double offset = receive - static_cast<double>(f.transmit) / freq;
            if (!have_offset_ || offset < clock_offset_s_) clock_offset_s_ = offset;
            have_offset_ = true;
            return static_cast<double>(f.mid_exposure) / freq + clock_offset_s_;
        }
    }
    return receive;
}

FrameConverter::Output FrameConverter::convert(const FrameOfData& f, Nanos receive_wall_ns, bool* refused) {
    Output out;
    if (refused) *refused = false;
    if (!kMotiveClockRange.contains(f.timestamp_s)) {  // no clock to estimate velocities or staleness on
        ++implausible_;
        if (refused) *refused = true;
        return out;
    }
    if (last_frame_ >= 0 && f.frame_number > last_frame_ + 1)
        dropped_ += static_cast<std::uint64_t>(f.frame_number - last_frame_ - 1);
    last_frame_ = f.frame_number;
    const double t = camera_time_s(f, receive_wall_ns);
    // Velocities and staleness run on Motive's own frame clock: exact spacing, whatever the
    // network's jitter did to the receive times. It restarts with Motive: so do the estimators.
    const double tc = f.timestamp_s;
    if (tc < last_camera_s_) tracks_.clear();
    last_camera_s_ = tc;
    const double freq = server_.clock_frequency ? static_cast<double>(server_.clock_frequency) : 1.0;
    auto& m = out.frame;
    m.header().stamp(dds::to_msg(from_seconds(t)));
    m.frame_number(static_cast<std::uint64_t>(f.frame_number));
    m.camera_mid_exposure(dds::to_msg(from_seconds(static_cast<double>(f.mid_exposure) / freq)));
    m.transmit(dds::to_msg(from_seconds(static_cast<double>(f.transmit) / freq)));
    m.receive(dds::to_msg(receive_wall_ns));
    m.timestamp_mode(options_.mode);
    m.dropped_frames(static_cast<std::uint32_t>(dropped_));
    for (const auto& b : f.bodies) {
        m.bodies().push_back(lab_body(b));
        if (!names_.contains(b.id)) {
            ++undefined_;
            continue;
        }
        out.states.push_back(vehicle_state(m.bodies().back(), m.header().stamp(), tc));
    }
    return out;
}

namespace {

// Least-squares slope over the recent samples, on their own time stamps: a dropped frame only
// widens the spacing. Nothing with fewer than two samples or no spread in time.
std::optional<std::array<double, 3>> slope(const std::vector<std::pair<double, std::array<double, 3>>>& recent) {
    if (recent.size() < 2) return std::nullopt;
    double mt = 0;
    for (const auto& [ti, pi] : recent) mt += ti;
    mt /= static_cast<double>(recent.size());
    double den = 0;
    std::array<double, 3> num{};
    for (const auto& [ti, pi] : recent) {
        den += (ti - mt) * (ti - mt);
        for (std::size_t k = 0; k < 3; ++k) num[k] += (ti - mt) * pi[k];
    }
    if (den <= 0) return std::nullopt;
    return std::array<double, 3>{num[0] / den, num[1] / den, num[2] / den};
}

}  // namespace

namespace {

bool finite(const RigidBody& b) {
    const auto ok = [](float x) { return std::isfinite(x); };
    return std::all_of(b.position.begin(), b.position.end(), ok) &&
           std::all_of(b.orientation.begin(), b.orientation.end(), ok) && std::isfinite(b.mean_error);
}

// Beyond physics::kMaxPlausiblePositionM of the origin a body is garbage, as is a non-finite
// position, orientation or error.
bool plausible(const RigidBody& b) {
    const auto& p = b.position;
    const auto& q = b.orientation;
    return finite(b) && dw::physics::plausible_orientation(Eigen::Vector4f(q[0], q[1], q[2], q[3]).cast<double>()) &&
           dw::physics::plausible_position(Eigen::Vector3f(p[0], p[1], p[2]).cast<double>());
}

}  // namespace

msg::RigidBody FrameConverter::lab_body(const RigidBody& in) {
    RigidBody b = in;
    if (b.tracking_valid ? !plausible(b) : !finite(b)) {  // passed on as lost: no pose, as Motive sends one
        ++implausible_;
        b = RigidBody{};
        b.id = in.id;
    }
    const auto& ax = options_.axes;
    msg::RigidBody r;
    auto it = names_.find(b.id);
    const std::string motive_name = it == names_.end() ? "body" + std::to_string(b.id) : it->second;
    auto mapped = options_.names.find(motive_name);
    r.name(mapped == options_.names.end() ? motive_name : mapped->second);
    r.id(b.id);
    std::array<double, 3> p{};
    std::array<double, 3> qv{};
    for (std::size_t i = 0; i < 3; ++i) {
        p[i] = ax.sign[i] * static_cast<double>(b.position[static_cast<std::size_t>(ax.source[i])]);
        // The quaternion's vector part is an axial vector: a reflection flips it once more.
        qv[i] = ax.det() * ax.sign[i] * static_cast<double>(b.orientation[static_cast<std::size_t>(ax.source[i])]);
    }
    r.position_m().x(p[0]);
    r.position_m().y(p[1]);
    r.position_m().z(p[2]);
    r.orientation().w(b.orientation[3]);
    r.orientation().x(qv[0]);
    r.orientation().y(qv[1]);
    r.orientation().z(qv[2]);
    r.tracking_valid(b.tracking_valid);
    r.residual_m(b.mean_error);
    return r;
}

FrameConverter::Held FrameConverter::held() const {
    Held h;
    h.bodies = tracks_.size();
    tracks_.for_each([&](std::int32_t, const Track& t) { h.samples += t.recent.size(); });
    return h;
}

msg::VehicleState FrameConverter::vehicle_state(const msg::RigidBody& r, const msg::Time& stamp, double tc) {
    Track& tr = tracks_[r.id()];
    msg::VehicleState s;
    s.header().stamp(stamp);
    s.vehicle_id(r.name());
    s.tracking_valid(r.tracking_valid());
    if (r.tracking_valid()) {
        if (tr.last_valid_s >= 0 && tc - tr.last_valid_s > options_.reset_gap_s)
            tr.recent.clear();  // back after a loss
        tr.recent.emplace_back(tc, std::array<double, 3>{r.position_m().x(), r.position_m().y(), r.position_m().z()});
        while (tr.recent.size() > 2 &&
               (tc - tr.recent.front().first > options_.velocity_window_s || tr.recent.size() > kMaxRecentSamples))
            tr.recent.erase(tr.recent.begin());
        tr.last_valid_s = tc;
        s.position_m(r.position_m());
        s.orientation(r.orientation());
    } else if (!tr.recent.empty()) {
        const auto& last = tr.recent.back().second;  // hold the last known pose
        s.position_m().x(last[0]);
        s.position_m().y(last[1]);
        s.position_m().z(last[2]);
    }
    const auto v = r.tracking_valid() ? slope(tr.recent) : std::nullopt;
    if (v) {
        s.velocity_mps().x((*v)[0]);
        s.velocity_mps().y((*v)[1]);
        s.velocity_mps().z((*v)[2]);
    }
    s.staleness_s(tr.last_valid_s < 0 ? -1.0 : tc - tr.last_valid_s);
    s.airborne(true);
    return s;
}

}  // namespace dw::natnet
