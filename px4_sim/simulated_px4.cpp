#include "px4_sim/simulated_px4.hpp"

#include <chrono>
#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/time.hpp"

namespace dw::px4sim {
namespace px4 = dds::px4;

namespace {
constexpr double kFollowRate = 20.0;               // 1/s: how fast the simulated vehicle closes on its setpoint
constexpr double kLandSpeed = 0.7;                 // m/s in AUTO_LAND
constexpr double kGroundTolerance = 0.02;          // m: landed
constexpr double kWantTakeoff_m = 0.2;             // a setpoint this far above it asks for a take-off
constexpr double kQuaternionNormTolerance = 1e-5;  // EKF2's check on vehicle_visual_odometry.q
constexpr std::uint8_t kNavPosctl = 2;             // after boot
constexpr double kGravity = 9.81;                  // m/s²: a killed vehicle falls
const std::string kTypePrefix = "px4_msgs::msg::dds_::";

std::string type_name(std::string_view msg) { return kTypePrefix + std::string(msg) + "_"; }
}  // namespace

struct SimulatedPx4::State {
    physics::Vec3 x = physics::Vec3::Zero();  // local NED
    std::optional<physics::Vec3> setpoint;    // local NED
    double ground_z = 0;
    bool armed = false;
    std::uint8_t nav = kNavPosctl, intention = kNavPosctl;
    bool failsafe = false;
    std::uint8_t disarm_reason = 0;  // latest_disarming_reason
    bool killed = false, battery_low = false;
    double fall_speed = 0;                        // m/s, once killed
    Nanos armed_ns = 0, killed_ns = 0;            // monotonic
    Nanos landed_ns = 0;                          // monotonic: when the land detector saw it on the ground (0: not)
    Nanos ramp_ns = 0;                            // monotonic: the take-off ramp's start (0: none yet)
    std::uint64_t takeoff_us = 0;                 // vehicle_status.takeoff_time: lift-off (0: on the ground)
    Nanos stream_since_ns = 0, last_mode_ns = 0;  // monotonic: the offboard stream's start and last sample
    std::uint64_t last_mode_us = 0;               // its timestamp, as PX4 reads it (this host's realtime µs)
    bool mode_flag = false, position_flag = false;
    Nanos odometry_ns = 0;        // the last odometry EKF2 would accept
    Nanos odometry_since_ns = 0;  // the start of its unbroken run (EKF2's warm-up counts from it)
    Nanos boot_ns = 0;            // monotonic: when it started (an onboard warm-up counts from it)
    bool was_synced = true;       // its time synchroniser, at the last step
    bool status_changed = true;
    std::vector<std::vector<std::uint8_t>> acks;  // to publish from the loop
    Report report;
};

SimulatedPx4::SimulatedPx4(dds::Participant& lab, const dds::DdsConfig& px4_side, SimulatedPx4Options o)
    : o_(std::move(o)),
      lab_(lab),
      s_(std::make_unique<State>()),
      states_(o_.publish_state ? std::make_unique<dds::Writer<msg::VehicleState>>(lab, dds::topics::vehicle_state)
                               : nullptr),
      px4_(px4_side, "px4_" + o_.vehicle) {
    const bool onboard = o_.position_source == PositionSource::onboard;
    o_.frame.origin.z() -= o_.origin_above_floor_m.value_or(onboard ? kOnboardOriginAboveFloor_m : 0.0);
    wander_m_ = o_.estimate_wander_m.value_or(onboard ? kOnboardWander_m : 0.0);
    s_->x = o_.frame.point(o_.parked);
    s_->boot_ns = lab_.clock().monotonic_ns();
    s_->ground_z = s_->x.z();
    const auto in = [&](std::string_view t) { return dds::px4_topic(o_.ns, "in", t); };
    px4_.subscribe(in("offboard_control_mode"), type_name("OffboardControlMode"), [this](auto b) { on_mode(b); });
    px4_.subscribe(in("trajectory_setpoint"), type_name("TrajectorySetpoint"), [this](auto b) { on_trajectory(b); });
    px4_.subscribe(in("vehicle_visual_odometry"), type_name("VehicleOdometry"), [this](auto b) { on_odometry(b); });
    if (o_.reads_commands)
        px4_.subscribe(in("vehicle_command"), type_name("VehicleCommand"), [this](auto b) { on_command(b); });
    thread_ = std::jthread([this](std::stop_token st) { loop(st); });
}

SimulatedPx4::~SimulatedPx4() {
    thread_.request_stop();
    if (thread_.joinable()) thread_.join();
}

physics::Vec3 SimulatedPx4::lab_position() const {
    std::lock_guard lock(mutex_);
    return o_.frame.lab_point(s_->x);
}

SimulatedPx4::Report SimulatedPx4::report() const {
    std::lock_guard lock(mutex_);
    Report r = s_->report;
    r.armed = s_->armed;
    r.nav_state = s_->nav;
    r.local_position = local_position(lab_.clock().monotonic_ns());
    return r;
}

void SimulatedPx4::event(const std::string& line) {
    s_->report.events.push_back(line);
    log::debug("simulated PX4 ", o_.system_id, ": ", line);
}

std::optional<Values> SimulatedPx4::decode_or_count(Msg m, std::span<const std::uint8_t> b) {
    try {
        return decode(msg_def(m, o_.version), b);
    } catch (const InputError& e) {
        std::lock_guard lock(mutex_);
        ++s_->report.undecodable;
        event(e.what());
        return std::nullopt;
    }
}

// The test's cut link: after `lose_offboard_after_s` armed, the planner's stream no longer arrives.
bool SimulatedPx4::link_cut(Nanos mono) const {
    return s_->armed && o_.lose_offboard_after_s && to_seconds(mono - s_->armed_ns) > *o_.lose_offboard_after_s;
}

bool SimulatedPx4::synced(Nanos mono) const {
    if (o_.time_jump_every_s <= 0) return true;
    const double t = to_seconds(mono - s_->boot_ns);
    return t < o_.time_jump_every_s || std::fmod(t, o_.time_jump_every_s) >= o_.time_resync_s;
}

std::uint64_t SimulatedPx4::boot_us() const {
    return std::max<std::uint64_t>(1, static_cast<std::uint64_t>((lab_.clock().monotonic_ns() - s_->boot_ns) / 1000));
}

double SimulatedPx4::stamp_out_us() const {
    const Nanos mono = lab_.clock().monotonic_ns();
    return static_cast<double>(synced(mono) ? lab_.clock().now_ns() / 1000 : (mono - s_->boot_ns) / 1000);
}

std::uint64_t SimulatedPx4::stamp_in_us(double stamp) const {
    const auto now_us = static_cast<std::uint64_t>(lab_.clock().now_ns() / 1000);
    if (stamp == 0 || stamp >= static_cast<double>(now_us) || !synced(lab_.clock().monotonic_ns())) return now_us;
    return static_cast<std::uint64_t>(stamp);
}

void SimulatedPx4::on_mode(std::span<const std::uint8_t> b) {
    const auto v = decode_or_count(Msg::offboard_control_mode, b);
    if (!v) return;
    const Nanos mono = lab_.clock().monotonic_ns();
    std::lock_guard lock(mutex_);
    if (link_cut(mono)) return;
    const std::uint64_t ts = stamp_in_us(value(*v, "timestamp"));
    if (s_->last_mode_ns == 0 || to_seconds(mono - s_->last_mode_ns) > o_.com_of_loss_t_s) s_->stream_since_ns = mono;
    s_->last_mode_ns = mono;
    s_->last_mode_us = ts;
    s_->position_flag = value(*v, "position") != 0;
    s_->mode_flag = s_->position_flag || value(*v, "velocity") != 0 || value(*v, "acceleration") != 0 ||
                    value(*v, "attitude") != 0 || value(*v, "body_rate") != 0;
}

void SimulatedPx4::on_trajectory(std::span<const std::uint8_t> b) {
    const auto v = decode_or_count(Msg::trajectory_setpoint, b);
    if (!v) return;
    const auto& p = v->at("position");
    const physics::Vec3 sp(p[0], p[1], p[2]);
    std::lock_guard lock(mutex_);
    if (link_cut(lab_.clock().monotonic_ns())) return;
    if (sp.allFinite()) s_->setpoint = sp;
}

void SimulatedPx4::on_odometry(std::span<const std::uint8_t> b) {
    const auto v = decode_or_count(Msg::vehicle_odometry, b);
    if (!v) return;
    const auto& q = v->at("q");
    const auto& p = v->at("position");
    const double frame = value(*v, "pose_frame");
    const double norm = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    const bool ok = (frame == px4::kFrameNed || frame == px4::kFrameFrd) && std::isfinite(norm) &&
                    std::abs(norm - 1.0) <= kQuaternionNormTolerance && std::isfinite(p[0]) && std::isfinite(p[1]) &&
                    std::isfinite(p[2]);
    const Nanos mono = lab_.clock().monotonic_ns();
    std::lock_guard lock(mutex_);
    if (s_->armed && o_.lose_vision_after_s && to_seconds(mono - s_->armed_ns) > *o_.lose_vision_after_s) return;
    if (!ok) {
        ++s_->report.rejected_odometry;
        return;
    }
    if (s_->odometry_ns == 0 || to_seconds(mono - s_->odometry_ns) > o_.position_timeout_s)
        s_->odometry_since_ns = mono;
    s_->odometry_ns = mono;
}

bool SimulatedPx4::local_position(Nanos mono) const {
    if (o_.position_source == PositionSource::onboard) return to_seconds(mono - s_->boot_ns) >= o_.ekf_warmup_s;
    return s_->odometry_ns != 0 && to_seconds(mono - s_->odometry_ns) <= o_.position_timeout_s &&
           to_seconds(mono - s_->odometry_since_ns) >= o_.ekf_warmup_s;
}

void SimulatedPx4::on_command(std::span<const std::uint8_t> b) {
    const auto v = decode_or_count(Msg::vehicle_command, b);
    if (!v) return;
    const auto target = static_cast<int>(value(*v, "target_system"));
    const auto component = static_cast<int>(value(*v, "target_component"));
    std::lock_guard lock(mutex_);
    if ((target != o_.system_id && target != 0) || (component != px4::kAutopilotComponent && component != 0)) {
        ++s_->report.ignored_commands;  // Commander::handle_command returns false: no ack, no log
        event(log::cat("ignored command ", value(*v, "command"), " for system ", target, " component ", component));
        return;
    }
    std::string why;
    const auto result = commander(*v, why);
    event(log::cat("command ", value(*v, "command"), ": ", px4::ack_result_name(static_cast<std::uint8_t>(result)),
                   why.empty() ? "" : " (" + why + ")"));
    Values ack{{"timestamp", {stamp_out_us()}},
               {"command", {value(*v, "command")}},
               {"result", {static_cast<double>(result)}},
               {"target_system", {value(*v, "source_system")}},
               {"target_component", {value(*v, "source_component")}},
               {"from_external", {0}}};
    s_->acks.push_back(encode(msg_def(Msg::vehicle_command_ack, o_.version), ack));
}

dds::px4::AckResult SimulatedPx4::commander(const Values& cmd, std::string& why) {
    using R = px4::AckResult;
    const Nanos mono = lab_.clock().monotonic_ns();
    const bool position = local_position(mono);
    const auto now_us = static_cast<std::uint64_t>(lab_.clock().now_ns() / 1000);
    const double stream_age_s =
        (static_cast<double>(now_us) - static_cast<double>(s_->last_mode_us)) * 1e-6;  // signed: a clock step back
    const bool fresh = s_->last_mode_us != 0 && stream_age_s < o_.com_of_loss_t_s &&
                       to_seconds(mono - s_->last_mode_ns) < o_.com_of_loss_t_s;
    const auto command = static_cast<std::uint32_t>(value(cmd, "command"));
    const double p1 = value(cmd, "param1");
    if (command == px4::kCmdDoSetMode) {
        const bool custom = std::isfinite(p1) && p1 >= 0 && p1 < 256 &&
                            (static_cast<int>(p1) & 1);  // PX4 reads param1 as uint8 base_mode
        if (!(custom && value(cmd, "param2") == px4::kCustomMainModeOffboard))
            return why = "only OFFBOARD is simulated", R::unsupported;
        if (!fresh || !s_->mode_flag) return why = "no offboard_control_mode stream", R::temporarily_rejected;
        if (to_seconds(mono - s_->stream_since_ns) < o_.offboard_warmup_s)
            return why = "offboard stream shorter than 1 s", R::temporarily_rejected;
        if (s_->position_flag && !position) return why = "no local position", R::temporarily_rejected;
        s_->nav = s_->intention = px4::kNavOffboard;
        s_->report.was_offboard = s_->status_changed = true;
        return R::accepted;
    }
    if (command == px4::kCmdArmDisarm) {
        if (p1 == 0) return s_->armed = false, s_->status_changed = true, R::accepted;
        if (!o_.refuse_arm.empty()) return why = o_.refuse_arm, R::denied;
        if (!position) return why = "no local position", R::denied;
        s_->armed = s_->report.was_armed = s_->status_changed = true;
        s_->armed_ns = mono;
        s_->ramp_ns = 0;  // a new take-off
        s_->takeoff_us = 0;
        return R::accepted;
    }
    if (command == px4::kCmdNavLand) {
        s_->nav = s_->intention = px4::kNavAutoLand;
        s_->status_changed = true;
        return R::accepted;
    }
    return why = "not simulated", R::unsupported;
}

void SimulatedPx4::step(double dt) {
    auto& s = *s_;
    const Nanos mono = lab_.clock().monotonic_ns();
    if (s.nav == px4::kNavOffboard && to_seconds(mono - s.last_mode_ns) > o_.com_of_loss_t_s) {
        s.nav = px4::kNavAutoLand;  // COM_OBL_RC_ACT = 4 (Land); the user's intention stays OFFBOARD
        s.failsafe = s.status_changed = true;
        event("offboard stream lost for over COM_OF_LOSS_T: failsafe, AUTO_LAND");
    }
    if (!s.armed) return;
    if (s.takeoff_us != 0 && s.nav != px4::kNavDescend && !local_position(mono)) {
        s.nav = px4::kNavDescend;  // no position to land at: descend where it is
        s.failsafe = s.status_changed = true;
        event("no local position (vision lost): failsafe, blind land (DESCEND)");
    }
    faults(mono);
    if (s.killed) {  // motors stopped: it falls, and PX4 disarms after COM_KILL_DISARM
        s.fall_speed += kGravity * dt;
        s.x.z() = std::min(s.ground_z, s.x.z() + s.fall_speed * dt);
        if (to_seconds(mono - s.killed_ns) >= o_.com_kill_disarm_s) disarm(px4::kDisarmKillSwitch, "killed: disarmed");
        return;
    }
    if (s.nav == px4::kNavOffboard && s.setpoint) follow(dt, mono);
    if (s.nav == px4::kNavAutoLand || s.nav == px4::kNavDescend) {
        s.x.z() = std::min(s.ground_z, s.x.z() + kLandSpeed * dt);
        const bool on_ground = s.x.z() >= s.ground_z - kGroundTolerance;
        if (!on_ground) s.landed_ns = 0;
        else if (s.landed_ns == 0) s.landed_ns = mono;
        if (on_ground && to_seconds(mono - s.landed_ns) >= o_.com_disarm_land_s)
            disarm(px4::kDisarmAfterLanding, "landed: disarmed");
    }
}

// Offboard flight: spool-up, then the take-off ramp (vertical only until airborne), then the setpoints.
void SimulatedPx4::follow(double dt, Nanos mono) {
    auto& s = *s_;
    const physics::Vec3 target = *s.setpoint;
    if (to_seconds(mono - s.armed_ns) < o_.com_spoolup_time_s) return;  // the motors spooling up
    if (s.ramp_ns == 0) {
        if (target.z() > s.x.z() - kWantTakeoff_m) return;  // nothing asks it up
        s.ramp_ns = mono;
        event("take-off: climb ramp started");
    }
    if (o_.land_detector_fooled) {  // says airborne, never lifts
        if (s.takeoff_us == 0) {
            s.takeoff_us = boot_us();
            s.status_changed = true;
            event("airborne (land detector)");
        }
        return;
    }
    const double ramped = to_seconds(mono - s.ramp_ns);
    if (ramped >= o_.mpc_tko_ramp_t_s && s.takeoff_us != 0) {
        s.x += (target - s.x) * std::min(1.0, kFollowRate * dt);
        return;
    }
    const double climb = o_.mpc_tko_speed_mps * std::min(1.0, ramped / o_.mpc_tko_ramp_t_s);
    const double up = std::clamp((target.z() - s.x.z()) * kFollowRate, -climb, climb);
    if (s.takeoff_us != 0) {  // airborne: horizontal control too
        s.x.x() += (target.x() - s.x.x()) * std::min(1.0, kFollowRate * dt);
        s.x.y() += (target.y() - s.x.y()) * std::min(1.0, kFollowRate * dt);
    }
    s.x.z() = std::min(s.ground_z, s.x.z() + up * dt);
    if (s.takeoff_us == 0 && s.x.z() < s.ground_z - kGroundTolerance) {
        s.takeoff_us = boot_us();
        s.status_changed = true;
        event("airborne (land detector)");
    }
}

// The faults a test throws in flight: the kill switch, and the battery at its failsafe level
// (COM_LOW_BAT_ACT = 3: land; vehicle_status shows the failsafe, not its cause).
void SimulatedPx4::faults(Nanos mono) {
    auto& s = *s_;
    const double armed_for = to_seconds(mono - s.armed_ns);
    if (o_.kill_after_s && !s.killed && armed_for > *o_.kill_after_s) {
        s.killed = true;
        s.killed_ns = mono;
        event("kill switch: motors stopped");
    }
    if (o_.low_battery_after_s && !s.battery_low && armed_for > *o_.low_battery_after_s) {
        s.battery_low = true;
        s.nav = px4::kNavAutoLand;
        s.failsafe = s.status_changed = true;
        event("battery below its failsafe level: failsafe, AUTO_LAND");
    }
}

void SimulatedPx4::disarm(std::uint8_t reason, const std::string& why) {
    s_->armed = false;
    s_->disarm_reason = reason;
    s_->status_changed = true;
    event(why);
}

void SimulatedPx4::publish_status() {
    std::vector<std::uint8_t> bytes;
    std::vector<std::vector<std::uint8_t>> acks;
    {
        std::lock_guard lock(mutex_);
        const auto& s = *s_;
        const double armed = s.armed ? px4::kArmed : 1.0;  // 1: STANDBY (1.14) or DISARMED (1.15+)
        Values v{{"timestamp", {stamp_out_us()}},
                 {"arming_state", {armed}},
                 {"takeoff_time", {static_cast<double>(s.takeoff_us)}},
                 {"nav_state", {static_cast<double>(s.nav)}},
                 {"nav_state_user_intention", {static_cast<double>(s.intention)}},
                 {"failsafe", {s.failsafe ? 1.0 : 0.0}},
                 {"latest_disarming_reason", {static_cast<double>(s.disarm_reason)}},
                 {"system_id", {static_cast<double>(o_.system_id)}},
                 {"component_id", {static_cast<double>(px4::kAutopilotComponent)}},
                 {"pre_flight_checks_pass",
                  {o_.refuse_arm.empty() && local_position(lab_.clock().monotonic_ns()) ? 1.0 : 0.0}}};
        bytes = encode(msg_def(Msg::vehicle_status, o_.version), v);
        acks.swap(s_->acks);
        s_->status_changed = false;
    }
    const auto& version = dds::px4_version(o_.version);
    px4_.publish(dds::px4_topic(o_.ns, "out", version.status_topic), type_name("VehicleStatus"), bytes);
    if (!o_.publishes_ack.value_or(version.ack_bridged)) return;  // PX4 answered; nothing bridges it
    for (const auto& a : acks)
        px4_.publish(dds::px4_topic(o_.ns, "out", version.ack_topic), type_name("VehicleCommandAck"), a);
}

// EKF2's estimate as PX4 bridges it (fmu/out/vehicle_odometry): here the simulated truth, in its
// local NED. PX4's client adds its time-sync offset to outgoing stamps (SPECS.md §3): microseconds
// on the Agent host's clock, here this host's.
void SimulatedPx4::publish_estimate(const physics::Vec3& local_velocity) {
    std::vector<std::uint8_t> bytes;
    {
        std::lock_guard lock(mutex_);
        if (!local_position(lab_.clock().monotonic_ns())) return;
        const double now_us = stamp_out_us();
        const physics::Vec3 x = s_->x + wander(lab_.clock().monotonic_ns());
        Values v{{"timestamp", {now_us}},
                 {"timestamp_sample", {now_us}},
                 {"pose_frame", {px4::kFrameNed}},
                 {"position", {x.x(), x.y(), x.z()}},
                 {"q", {1, 0, 0, 0}},
                 {"velocity_frame", {px4::kFrameNed}},
                 {"velocity", {local_velocity.x(), local_velocity.y(), local_velocity.z()}},
                 {"quality", {px4::kQualityBest}}};
        bytes = encode(msg_def(Msg::vehicle_odometry, o_.version), v);
    }
    px4_.publish(dds::px4_topic(o_.ns, "out", "vehicle_odometry"), type_name("VehicleOdometry"), bytes);
}

// The estimate's error: a slow wander (what a barometer and GPS do), from boot.
physics::Vec3 SimulatedPx4::wander(Nanos mono) const {
    const double phase = 2 * M_PI * to_seconds(mono - s_->boot_ns) / kWanderPeriod_s;
    return wander_m_ * physics::Vec3(0.5 * std::sin(phase), 0, std::sin(phase));
}

void SimulatedPx4::loop(std::stop_token stop) {
    const auto period = std::chrono::duration<double>(1.0 / o_.rate_hz);
    auto next = std::chrono::steady_clock::now();
    Nanos last_status = 0;
    while (!stop.stop_requested()) {
        msg::VehicleState st;
        bool status_due = false;
        physics::Vec3 local_velocity;
        {
            std::lock_guard lock(mutex_);
            const physics::Vec3 before = s_->x;
            step(period.count());
            const physics::Vec3 x = o_.frame.lab_point(s_->x);
            const physics::Vec3 v = o_.frame.lab_point(s_->x) - o_.frame.lab_point(before);
            local_velocity = (s_->x - before) / period.count();
            st.header().stamp(dds::to_msg(lab_.clock().now_ns()));
            st.vehicle_id(o_.vehicle);
            st.position_m().x(x.x()), st.position_m().y(x.y()), st.position_m().z(x.z());
            st.velocity_mps().x(v.x() / period.count()), st.velocity_mps().y(v.y() / period.count()),
                st.velocity_mps().z(v.z() / period.count());
            st.orientation().w(1.0);
            st.tracking_valid(true);
            st.armed(s_->armed);
            st.airborne(s_->x.z() < s_->ground_z - kGroundTolerance);
            const Nanos mono = lab_.clock().monotonic_ns();
            if (s_->was_synced && !synced(mono)) event("time jump detected. Resetting time synchroniser.");
            s_->was_synced = synced(mono);
            status_due =
                s_->status_changed || !s_->acks.empty() || to_seconds(mono - last_status) >= o_.status_period_s;
            if (status_due) last_status = mono;
        }
        if (states_) states_->write(st);
        publish_estimate(local_velocity);
        if (status_due) publish_status();
        next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
        std::this_thread::sleep_until(next);
    }
}

}  // namespace dw::px4sim
