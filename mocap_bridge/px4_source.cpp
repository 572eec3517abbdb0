#include "mocap_bridge/px4_source.hpp"

#include <cmath>
#include <limits>

#include "core/log.hpp"
#include "dds/time.hpp"
#include "flight/flight.hpp"

namespace dw::natnet {
namespace {

namespace px4 = dds::px4;

using px4_msgs::msg::dds_::VehicleOdometry_;
constexpr double kMaxPublishDelayS = 1.0;       // timestamp - timestamp_sample beyond this: not an age
constexpr std::int32_t kSuffererBodyId = 0;     // the stand's sufferer; vehicles are 1, 2, ...
constexpr float kUnknownResidual = -1.0f;       // an estimate has no marker error
constexpr std::uint64_t kSayUntiedEvery = 500;  // estimates (5 s at PX4's rate) between the untied lines

physics::Vec3 vec(const std::array<float, 3>& a) { return {a[0], a[1], a[2]}; }

msg::Vector3 to_msg(const physics::Vec3& v) {
    msg::Vector3 m;
    m.x(v.x()), m.y(v.y()), m.z(v.z());
    return m;
}

msg::Quaternion to_msg(const Eigen::Quaterniond& q) {
    msg::Quaternion m;
    m.w(q.w()), m.x(q.x()), m.y(q.y()), m.z(q.z());
    return m;
}

msg::RigidBody body(const std::string& name, std::int32_t id, const physics::Vec3& p, const Eigen::Quaterniond& q,
                    bool valid) {
    msg::RigidBody b;
    b.name(name);
    b.id(id);
    b.position_m(to_msg(p));
    b.orientation(to_msg(q));
    b.tracking_valid(valid);
    b.residual_m(kUnknownResidual);
    return b;
}

}  // namespace

Px4PoseSource::Px4PoseSource(dds::Participant& p, Px4SourceOptions o) : p_(p), o_(std::move(o)), armed_(p, o_.px4) {
    for (const auto& cfg : o_.px4.vehicles) {
        Vehicle& v = vehicles_.emplace_back();
        v.cfg = cfg;
        v.topic = dds::px4_topic(cfg.ns, "out", "vehicle_odometry");
        Vehicle* vp = &v;
        v.reader = std::make_unique<dds::Reader<VehicleOdometry_>>(
            p_, dds::px4_topic_spec<VehicleOdometry_>(v.topic, "px4_msgs::msg::dds_::VehicleOdometry_"),
            [this, vp](const VehicleOdometry_& m, const dds::SampleMeta&) { on_odometry(*vp, m); });
        log::info(cfg.name, ": poses from PX4's estimate on ", v.topic);
    }
}

void Px4PoseSource::on_odometry(Vehicle& v, const VehicleOdometry_& m) {
    const Nanos now = p_.clock().now_ns();
    const physics::Vec3 x = vec(m.position()), vel = vec(m.velocity());
    const Eigen::Quaterniond q(m.q()[0], m.q()[1], m.q()[2], m.q()[3]);
    const bool ok = m.pose_frame() == px4::kFrameNed && planner::usable_pose(x, q);
    // A velocity beyond what a multirotor can fly (a finite 1e30 m/s carried the pose 1e28 m on) is
    // unknown: the pose is held, not carried, and that sample cannot show the vehicle at rest.
    const bool moving_known = m.velocity_frame() == px4::kFrameNed && planner::usable_velocity(vel);
    std::lock_guard lock(mutex_);
    if (!ok) {
        if (rejected_++ == 0)
            log::warn(v.cfg.name, ": an estimate on ", v.topic, " is not a finite pose in NED (pose_frame ",
                      static_cast<int>(m.pose_frame()), "); such estimates are not used");
        return;
    }
    // The estimate's age when PX4 published it, on PX4's own clock (both stamps are PX4's).
    const double age_s = (static_cast<double>(m.timestamp()) - static_cast<double>(m.timestamp_sample())) * 1e-6;
    const Nanos age = age_s >= 0 && age_s <= kMaxPublishDelayS ? from_seconds(age_s) : 0;
    planner::LocalFrame f = planner::local_frame(v.cfg);
    if (o_.px4.ground == planner::GroundFrom::estimate) {  // not posed until its frame is tied to the floor
        const auto armed = armed_.armed(v.cfg.name);
        if (moving_known) v.tie.add(to_seconds(now), x, vel, armed && !*armed);
        if (!v.tie.tied()) {
            if (++v.untied % kSayUntiedEvery == 0) log::warn(v.cfg.name, ": not posed yet: ", v.tie.describe());
            return;
        }
        if (!v.tie_said) v.tie_said = true, log::info(v.cfg.name, ": ", v.tie.describe());
        f.origin.z() = -*v.tie.floor_d();
    }
    Estimate e;
    e.position = f.lab_point(x);
    e.velocity = moving_known ? f.lab_vector(vel) : physics::Vec3::Zero();
    e.attitude = f.lab_attitude(q.normalized());
    e.captured_ns = now - age;
    v.latest = e;
    ++received_;
}

Px4PoseSource::Output Px4PoseSource::frame(Nanos now_ns) {
    Output out;
    auto& m = out.frame;
    m.header().stamp(dds::to_msg(now_ns));
    m.receive(dds::to_msg(now_ns));
    m.timestamp_mode(msg::MOCAP_STAMP_RECEIVE);
    m.pose_source(msg::POSE_VEHICLE_ESTIMATE);
    if (o_.sufferer)
        m.bodies().push_back(
            body(flight::kSufferer, kSuffererBodyId, *o_.sufferer, Eigen::Quaterniond::Identity(), true));
    std::lock_guard lock(mutex_);
    m.frame_number(++frames_);
    std::int32_t id = kSuffererBodyId;
    for (const auto& v : vehicles_) {
        ++id;
        const double age =
            v.latest ? to_seconds(now_ns - v.latest->captured_ns) : std::numeric_limits<double>::infinity();
        const bool fresh = age <= o_.stale_s;
        // Carried to the frame's stamp by the estimated velocity (held where it is not fresh).
        physics::Vec3 p = physics::Vec3::Zero();
        if (v.latest) p = v.latest->position;
        if (fresh) p += v.latest->velocity * std::max(0.0, age);
        m.bodies().push_back(
            body(v.cfg.name, id, p, v.latest ? v.latest->attitude : Eigen::Quaterniond::Identity(), fresh));
        out.states.push_back(state_of(v, m.bodies().back(), now_ns));
    }
    return out;
}

msg::VehicleState Px4PoseSource::state_of(const Vehicle& v, const msg::RigidBody& b, Nanos now_ns) const {
    msg::VehicleState s;
    s.header().stamp(dds::to_msg(now_ns));
    s.vehicle_id(v.cfg.name);
    s.position_m(b.position_m());
    s.orientation(b.orientation());
    s.tracking_valid(b.tracking_valid());
    if (b.tracking_valid()) s.velocity_mps(to_msg(v.latest->velocity));
    s.staleness_s(v.latest ? to_seconds(now_ns - v.latest->captured_ns) : -1.0);
    s.airborne(true);  // as the motion capture bridge: it cannot tell
    return s;
}

std::uint64_t Px4PoseSource::received() const {
    std::lock_guard lock(mutex_);
    return received_;
}

std::uint64_t Px4PoseSource::rejected() const {
    std::lock_guard lock(mutex_);
    return rejected_;
}

}  // namespace dw::natnet
