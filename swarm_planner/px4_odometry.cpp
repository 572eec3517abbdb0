#include "swarm_planner/px4_odometry.hpp"

#include <algorithm>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "dds/time.hpp"

namespace dw::planner {
namespace {

namespace px4 = dds::px4;
using px4_msgs::msg::dds_::VehicleOdometry_;
constexpr std::size_t kLatencySamples = 500;  // odometry samples whose capture-to-send latency is logged

}  // namespace

Px4OdometryFeed::Px4OdometryFeed(dds::Participant& p, const Px4Options& o, bool subscribe) : p_(p), o_(o) {
    for (const auto& cfg : o_.vehicles) {
        Vehicle& v = vehicles_.emplace_back();
        v.frame = local_frame(cfg);
        v.topic = dds::px4_topic(cfg.ns, "in", "vehicle_visual_odometry");
        v.writer = std::make_unique<dds::Writer<VehicleOdometry_>>(
            p_, dds::px4_topic_spec<VehicleOdometry_>(v.topic, "px4_msgs::msg::dds_::VehicleOdometry_"));
        by_name_[cfg.name] = &v;
    }
    if (subscribe)
        states_ = std::make_unique<dds::Reader<msg::VehicleState>>(
            p_, dds::topics::vehicle_state,
            [this](const msg::VehicleState& s, const dds::SampleMeta&) { on_state(s); });
}

void Px4OdometryFeed::on_state(const msg::VehicleState& s) {
    const auto it = by_name_.find(s.vehicle_id());
    if (it == by_name_.end()) return;
    Vehicle& v = *it->second;
    const physics::Vec3 x(s.position_m().x(), s.position_m().y(), s.position_m().z());
    const Eigen::Quaterniond q(s.orientation().w(), s.orientation().x(), s.orientation().y(), s.orientation().z());
    const bool valid = s.tracking_valid() && usable_pose(x, q);
    std::lock_guard lock(mutex_);
    // Its stamp becomes the estimator's capture time: one that is no time here is not sent, and
    // does not end the vehicle's tracking either (a forged sample must not start a failsafe).
    if (!dds::stamp_in_time(dds::from_msg(s.header().stamp()), p_.clock().now_ns())) {
        if (untimely_++ == 0)
            log::warn(v.topic, ": a state of ", s.vehicle_id(), " stamped more than ", kMaxClockOffsetS,
                      " s from this clock is not sent (the first; counted)");
        return;
    }
    if (!valid) {
        v.tracking = false;
        return;
    }
    if (!v.tracking) ++v.reset_counter;  // tracking came back: the estimator may see a jump
    v.tracking = true;
    const Nanos now = p_.clock().monotonic_ns();
    if (o_.odometry_hz > 0 && v.sent_ns != 0 && to_seconds(now - v.sent_ns) < 1.0 / o_.odometry_hz) return;
    v.sent_ns = now;
    v.writer->write_as_is(odometry(v, s));
    note_latency(p_.clock().now_ns() - dds::from_msg(s.header().stamp()));
}

Nanos Px4OdometryFeed::last_sent_ns(const std::string& vehicle) const {
    std::lock_guard lock(mutex_);
    const auto it = by_name_.find(vehicle);
    return it == by_name_.end() ? 0 : it->second->sent_ns;
}

void Px4OdometryFeed::note_latency(Nanos capture_to_send) {  // under mutex_
    if (latencies_ms_.size() >= kLatencySamples) return;
    latencies_ms_.push_back(static_cast<double>(capture_to_send) * 1e-6);
    if (latencies_ms_.size() < kLatencySamples) return;
    auto sorted = latencies_ms_;
    std::nth_element(sorted.begin(), sorted.begin() + static_cast<std::ptrdiff_t>(sorted.size() / 2), sorted.end());
    log::info("odometry: capture to send median ", fixed(sorted[sorted.size() / 2], 1), " ms over ", kLatencySamples,
              " samples (EKF2_EV_DELAY: this plus the Agent's link; docs/OPERATOR.md)");
}

VehicleOdometry_ Px4OdometryFeed::odometry(const Vehicle& v, const msg::VehicleState& s) const {
    VehicleOdometry_ m;
    m.timestamp(static_cast<std::uint64_t>(p_.clock().now_ns() / 1000));
    m.timestamp_sample(static_cast<std::uint64_t>(dds::from_msg(s.header().stamp()) / 1000));  // the capture time
    m.pose_frame(px4::kFrameNed);
    m.velocity_frame(px4::kFrameNed);
    const physics::Vec3 p = v.frame.point(physics::Vec3(s.position_m().x(), s.position_m().y(), s.position_m().z()));
    const physics::Vec3 vel =
        v.frame.vector(physics::Vec3(s.velocity_mps().x(), s.velocity_mps().y(), s.velocity_mps().z()));
    const Eigen::Quaterniond q(s.orientation().w(), s.orientation().x(), s.orientation().y(), s.orientation().z());
    // Normalised in float, as EKF2 checks it (|‖q‖ - 1| <= 1e-5), w first (Hamilton, FRD -> NED).
    Eigen::Quaternionf ql = v.frame.attitude(q.normalized()).cast<float>();
    ql.normalize();
    const auto pv = static_cast<float>(o_.position_std_m * o_.position_std_m);
    const auto ov = static_cast<float>(o_.orientation_std_rad * o_.orientation_std_rad);
    const auto vv = static_cast<float>(o_.velocity_std_mps * o_.velocity_std_mps);
    m.q() = {ql.w(), ql.x(), ql.y(), ql.z()};
    for (std::size_t k = 0; k < 3; ++k) {
        m.position()[k] = static_cast<float>(p[static_cast<int>(k)]);
        m.velocity()[k] = usable_velocity(vel) ? static_cast<float>(vel[static_cast<int>(k)]) : px4::kUnset;
        m.angular_velocity()[k] = px4::kUnset;
        m.position_variance()[k] = pv;
        m.orientation_variance()[k] = ov;
        m.velocity_variance()[k] = vv;
    }
    m.reset_counter(v.reset_counter);
    m.quality(static_cast<std::uint8_t>(px4::kQualityBest));
    return m;
}

}  // namespace dw::planner
