#include "swarm_planner/px4_link.hpp"

#include <atomic>
#include <algorithm>
#include <deque>
#include <map>
#include <mutex>

#include "core/log.hpp"
#include "core/names.hpp"
#include "core/numbers.hpp"
#include "dds/px4.hpp"
#include "dds/time.hpp"
#include "swarm_planner/ground_tie.hpp"
#include "swarm_planner/px4_odometry.hpp"

namespace dw::planner {
namespace {

namespace px4 = dds::px4;
using px4_msgs::msg::dds_::TrajectorySetpoint_;

// The message types of one PX4 version (the others are the same in every supported version).
struct Types115 {
    using Mode = px4_msgs::msg::dds_::OffboardControlMode_;
    using Command = px4_msgs::msg::dds_::VehicleCommand_;
    using Status = px4_msgs::msg::dds_::VehicleStatus_;
    using Ack = px4_msgs::msg::dds_::VehicleCommandAck_;
};
struct Types116 : Types115 {
    using Status = px4_msgs_v116::msg::dds_::VehicleStatus_;  // vehicle_status_v1: no avoidance flags
};
struct Types114 {
    using Mode = px4_msgs_v114::msg::dds_::OffboardControlMode_;
    using Command = px4_msgs_v114::msg::dds_::VehicleCommand_;
    using Status = px4_msgs_v114::msg::dds_::VehicleStatus_;
    using Ack = px4_msgs_v114::msg::dds_::VehicleCommandAck_;
};

// What PX4 wants before OFFBOARD, as the link can see it from its own side.
constexpr double kStreamWarmupS = 1.0;  // setpoints streaming for more than this (PX4's offboard check)
constexpr double kStreamGapS = 0.5;     // no setpoint for longer than this: the stream has stopped (PX4: 2 Hz)
constexpr double kOdometryGapS = 0.5;   // no visual odometry for longer than this: EKF2 loses the position

// Each arming step: the command that asks for it and what vehicle_status shows when it is done.
// await_estimator: PX4's pre-flight checks (its estimator's local position among them) pass.
enum class Step { await_status, await_estimator, offboard, arm, ready, refused };

struct StatusSeen {
    std::uint8_t arming = 0, nav = 0, intention = 0, disarm_reason = 0;
    bool failsafe = false;
    bool preflight_ok = false;  // pre_flight_checks_pass
    Nanos seen_ns = 0;          // monotonic; 0 = never
    Nanos airborne_ns = 0;      // monotonic: when takeoff_time was first seen set (its land detector); 0 = not
};
struct AckSeen {
    std::uint32_t command = 0;
    std::uint8_t result = 0;
    Nanos seen_ns = 0;
};

template <class Types>
class Px4Link final : public VehicleLink {
public:
    Px4Link(dds::Participant& p, const Px4Options& o, const std::string& run_id)
        : p_(p), o_(o), record_(p, names_of(o), run_id), run_id_(run_id), commands_(p, dds::topics::vehicle_command) {
        for (std::size_t i = 0; i < o.vehicles.size(); ++i) add_vehicle(o.vehicles[i]);
        if (o.odometry == OdometryBy::planner) odometry_ = std::make_unique<Px4OdometryFeed>(p, o, true);
        log::info("PX4 link (", dds::px4_version(o.version).name, "): ", o.vehicles.size(), " vehicles, odometry ",
                  o.odometry == OdometryBy::planner
                      ? log::cat(o.odometry_hz > 0 ? o.odometry_hz : 0.0, " Hz (0 = every mocap frame)")
                      : log::cat("by ", name_of(kOdometryByNames, o.odometry)));
    }

    void deliver(const std::vector<std::optional<physics::Setpoint>>& sps, Nanos now_ns) override {
        const auto us = static_cast<std::uint64_t>(now_ns / 1000);
        const Nanos mono = p_.clock().monotonic_ns();
        for (std::size_t i = 0; i < sps.size() && i < vehicles_.size(); ++i) {
            if (!sps[i]) continue;  // the last gate let nothing through for it
            Vehicle& v = vehicles_[i];
            typename Types::Mode mode;  // proof of life, with every setpoint (PX4 wants > 2 Hz)
            mode.timestamp(us);
            mode.position(true);
            mode.velocity(true);
            mode.acceleration(true);
            v.mode->write_as_is(mode);
            v.traj->write_as_is(trajectory(frame_of(v), *sps[i], us));
            if (v.stream_last_ns == 0 || to_seconds(mono - v.stream_last_ns) > kStreamGapS) v.stream_since_ns = mono;
            v.stream_last_ns = mono;
        }
        record_.write(sps, now_ns);  // what was commanded, in the lab's frame, for the recording
    }

    // PX4's own estimate of where the vehicle is, through the frame the link commands in: an abort
    // never sends it above that, whatever the lab's poses say.
    std::optional<double> down_of(std::size_t i) override {
        if (i >= vehicles_.size()) return std::nullopt;
        std::lock_guard lock(mutex_);
        const auto& e = vehicles_[i].estimate;
        if (e.seen_ns == 0 || !(to_seconds(p_.clock().monotonic_ns() - e.seen_ns) <= kPositionFreshS))
            return std::nullopt;
        return e.lab_d;
    }

    ArmProgress arm() override {
        const Nanos now = p_.clock().monotonic_ns();
        ArmProgress out{ArmProgress::State::ready, ""};
        for (auto& v : vehicles_) {
            if (v.step_since == 0) v.step_since = now;
            advance(v, now);
            if (v.step == Step::refused) return {ArmProgress::State::refused, v.cfg.name + ": " + v.refusal};
            if (v.step != Step::ready) out.state = ArmProgress::State::pending;
        }
        return out;
    }

    std::optional<std::string> failsafe() override {
        const Nanos now = p_.clock().monotonic_ns();
        for (auto& v : vehicles_) {
            const StatusSeen s = status_of(v);
            const double age = to_seconds(now - s.seen_ns);
            if (!(age <= o_.status_timeout_s))
                return log::cat(v.cfg.name, ": no vehicle_status from PX4 for ", age,
                                " s (its link or the Agent lost)");
            // vehicle_status names a disarm's reason (a kill switch among them) but not a failsafe's
            // trigger: that is in PX4's failsafe_flags, which the link does not read (not yet).
            const std::string why =
                s.failsafe ? " (PX4 failsafe: offboard signal lost, low battery or another check; vehicle_status does "
                             "not say which)"
                           : "";
            if (s.arming != px4::kArmed)
                return log::cat(v.cfg.name, ": PX4 disarmed in flight by ", px4::disarm_reason_name(s.disarm_reason),
                                why);
            if (s.nav != px4::kNavOffboard)
                return log::cat(v.cfg.name, ": PX4 left OFFBOARD for ", px4::nav_state_name(s.nav), why);
        }
        return std::nullopt;
    }

    // No NAV_LAND to a vehicle PX4 reports disarmed: PX4 switches a disarmed vehicle on the ground
    // into AUTO_LAND too (seen on a real PX4 after a refused arm). A vehicle never heard from gets
    // it: landing is the safe side of not knowing.
    void land() override {
        for (auto& v : vehicles_) {
            const StatusSeen s = status_of(v);
            if (s.seen_ns == 0 || s.arming == px4::kArmed) command(v, px4::kCmdNavLand, 0.0f, 0.0f);
        }
    }

    // Landed is what PX4 says: disarmed (its land detector disarms after COM_DISARM_LAND). A vehicle
    // never heard from cannot be confirmed.
    std::optional<std::string> still_flying() override {
        std::vector<std::string> up;
        for (auto& v : vehicles_) {
            const StatusSeen s = status_of(v);
            if (s.seen_ns == 0) up.push_back(v.cfg.name + " (no vehicle_status)");
            else if (s.arming == px4::kArmed)
                up.push_back(log::cat(v.cfg.name, " (armed, ", px4::nav_state_name(s.nav), ")"));
        }
        if (up.empty()) return std::nullopt;
        return log::join(up);
    }
    double land_timeout_s() const override { return o_.land_timeout_s; }

    // Position control from the end of PX4's take-off ramp (MPC_TKO_RAMP_T, `takeoff_ramp_s`) after
    // its land detector saw the vehicle airborne; before that PX4 climbs straight up on the ramp.
    bool following(std::size_t i, std::string& how) override {
        if (i >= vehicles_.size()) return true;
        const StatusSeen s = status_of(vehicles_[i]);
        if (s.airborne_ns == 0) return how = "on the ground (PX4's land detector)", false;
        const double up = to_seconds(p_.clock().monotonic_ns() - s.airborne_ns);
        if (up < o_.takeoff_ramp_s)
            return how = log::cat("airborne for ", fixed(up, 1), " s, in its take-off ramp"), false;
        return true;
    }

private:
    struct Vehicle {
        Px4Vehicle cfg;
        LocalFrame frame;
        std::string traj_name, mode_name, cmd_name, status_name, ack_name;  // stable: specs view them
        std::unique_ptr<dds::Writer<TrajectorySetpoint_>> traj;
        std::unique_ptr<dds::Writer<typename Types::Mode>> mode;
        std::unique_ptr<dds::Writer<typename Types::Command>> cmd;
        std::unique_ptr<dds::Reader<typename Types::Status>> status;
        std::unique_ptr<dds::Reader<typename Types::Ack>> ack;
        std::unique_ptr<dds::Reader<px4_msgs::msg::dds_::VehicleOdometry_>> odometry;
        std::string odometry_name;
        StatusSeen st;                                  // under mutex_
        GroundTie tie;                                  // ground: estimate (under mutex_)
        std::atomic<std::uint64_t> absurd_odometry{0};  // PX4 estimates that are no pose (usable_pose), dropped
        struct {
            double lab_d = 0;                           // PX4's estimated D, in the lab's frame through `frame`
            Nanos seen_ns = 0;                          // monotonic; 0 = never
        } estimate;                                     // under mutex_
        AckSeen last_ack;                               // under mutex_
        Nanos stream_since_ns = 0, stream_last_ns = 0;  // the planner's setpoints, monotonic (planner's thread)
        Step step = Step::await_status;                 // arming: the planner's thread only
        int tries = 0;
        Nanos step_since = 0, first_sent_ns = 0, sent_ns = 0;  // monotonic
        Nanos cmd_matched_ns = 0;                              // monotonic: PX4's command reader first seen
        std::string refusal;
    };

    void add_vehicle(const Px4Vehicle& cfg) {
        Vehicle& v = vehicles_.emplace_back();
        v.cfg = cfg;
        v.frame = local_frame(cfg);
        const auto& version = dds::px4_version(o_.version);
        v.traj_name = dds::px4_topic(cfg.ns, "in", "trajectory_setpoint");
        v.mode_name = dds::px4_topic(cfg.ns, "in", "offboard_control_mode");
        v.cmd_name = dds::px4_topic(cfg.ns, "in", "vehicle_command");
        v.status_name = dds::px4_topic(cfg.ns, "out", version.status_topic);
        v.ack_name = dds::px4_topic(cfg.ns, "out", version.ack_topic);
        v.traj = std::make_unique<dds::Writer<TrajectorySetpoint_>>(
            p_, dds::px4_topic_spec<TrajectorySetpoint_>(v.traj_name, "px4_msgs::msg::dds_::TrajectorySetpoint_"));
        v.mode = std::make_unique<dds::Writer<typename Types::Mode>>(
            p_, dds::px4_topic_spec<typename Types::Mode>(v.mode_name, "px4_msgs::msg::dds_::OffboardControlMode_"));
        v.cmd = std::make_unique<dds::Writer<typename Types::Command>>(
            p_, dds::px4_topic_spec<typename Types::Command>(v.cmd_name, "px4_msgs::msg::dds_::VehicleCommand_"));
        Vehicle* vp = &v;
        // PX4's fmu/out writers are TRANSIENT_LOCAL, and the ack's appears with its first answer:
        // a transient-local reader still gets that answer once it has matched the new writer.
        dds::QosOverrides latest;
        latest.transient_local = true;
        v.status = std::make_unique<dds::Reader<typename Types::Status>>(
            p_, dds::px4_topic_spec<typename Types::Status>(v.status_name, "px4_msgs::msg::dds_::VehicleStatus_"),
            [this, vp](const typename Types::Status& s, const dds::SampleMeta&) {
                std::lock_guard lock(mutex_);
                const Nanos now = p_.clock().monotonic_ns();
                // takeoff_time is set by the Commander when the land detector sees the vehicle airborne.
                const bool took_off = s.arming_state() == px4::kArmed && s.takeoff_time() != 0;
                const Nanos airborne = !took_off ? 0 : vp->st.airborne_ns != 0 ? vp->st.airborne_ns : now;
                vp->st = {s.arming_state(),
                          s.nav_state(),
                          s.nav_state_user_intention(),
                          s.latest_disarming_reason(),
                          s.failsafe(),
                          s.pre_flight_checks_pass(),
                          now,
                          airborne};
            },
            latest);
        v.ack = std::make_unique<dds::Reader<typename Types::Ack>>(
            p_, dds::px4_topic_spec<typename Types::Ack>(v.ack_name, "px4_msgs::msg::dds_::VehicleCommandAck_"),
            [this, vp](const typename Types::Ack& a, const dds::SampleMeta&) {
                // An answer to someone else (a ground station is system 255 too) is not ours.
                if (a.target_system() != px4::kPlannerSystem || a.target_component() != px4::kPlannerComponent) return;
                std::lock_guard lock(mutex_);
                vp->last_ack = {a.command(), a.result(), p_.clock().monotonic_ns()};
            },
            latest);
        add_estimate_reader(v);
        by_name_[cfg.name] = &v;
    }

    static TrajectorySetpoint_ trajectory(const LocalFrame& f, const physics::Setpoint& sp, std::uint64_t us) {
        TrajectorySetpoint_ t;
        t.timestamp(us);
        const physics::Vec3 p = f.point(sp.position), vel = f.vector(sp.velocity), acc = f.vector(sp.acceleration);
        for (std::size_t k = 0; k < 3; ++k) {
            t.position()[k] = static_cast<float>(p[static_cast<int>(k)]);
            t.velocity()[k] = static_cast<float>(vel[static_cast<int>(k)]);
            t.acceleration()[k] = static_cast<float>(acc[static_cast<int>(k)]);
            t.jerk()[k] = px4::kUnset;
        }
        t.yaw(static_cast<float>(f.yaw(sp.yaw_rad)));
        t.yawspeed(px4::kUnset);
        return t;
    }

    void command(Vehicle& v, std::uint32_t command, float p1, float p2) {
        typename Types::Command c;
        c.timestamp(static_cast<std::uint64_t>(p_.clock().now_ns() / 1000));
        c.command(command);
        c.param1(p1);
        c.param2(p2);
        c.param5(px4::kUnset);
        c.param6(px4::kUnset);
        c.param7(px4::kUnset);
        c.target_system(static_cast<std::uint8_t>(v.cfg.system_id));  // PX4 ignores any other (but 0)
        c.target_component(px4::kAutopilotComponent);
        c.source_system(px4::kPlannerSystem);
        c.source_component(px4::kPlannerComponent);
        c.confirmation(0);
        c.from_external(true);
        v.cmd->write_as_is(c);
        record(v, c);
    }

    void record(const Vehicle& v, const typename Types::Command& c) {
        msg::VehicleCommandSent m;
        m.header().stamp(dds::to_msg(p_.clock().now_ns()));
        m.header().run_id(run_id_);
        m.vehicle_id(v.cfg.name);
        m.command(c.command());
        m.name(px4::command_name(c.command()));
        m.param1(c.param1());
        m.param2(c.param2());
        m.target_system(c.target_system());
        commands_.write(m);
    }

    StatusSeen status_of(const Vehicle& v) {
        std::lock_guard lock(mutex_);
        return v.st;
    }

    // One step of a vehicle's arming: ask, watch vehicle_status, retry, or refuse with the reason.
    void advance(Vehicle& v, Nanos now) {
        const StatusSeen s = status_of(v);
        const bool waiting = v.step == Step::await_status || v.step == Step::await_estimator;
        const double waited = to_seconds(now - (waiting ? v.step_since : v.sent_ns));
        switch (v.step) {
            case Step::await_status:
                // A command sent before PX4's command reader has matched would reach no one, nor one
                // sent before that reader has settled (dds::kMatchSettle: PX4 reads fmu/in best-effort).
                if (s.seen_ns != 0 && v.cmd->matched() > 0) {
                    if (v.cmd_matched_ns == 0) v.cmd_matched_ns = now;
                    if (now - v.cmd_matched_ns >= std::chrono::nanoseconds(dds::kMatchSettle).count())
                        return await_estimator(v, now);
                    return;
                }
                if (waited > o_.status_timeout_s && s.seen_ns != 0)
                    refuse(v, log::cat("PX4 publishes vehicle_status but nothing reads ", v.cmd_name, " after ", waited,
                                       " s (is vehicle_command among the Agent's bridged topics?)"));
                else if (waited > o_.status_timeout_s)
                    refuse(v, log::cat("no vehicle_status from PX4 on ", v.status_name, " in ", waited,
                                       " s (is the Agent running on domain ", p_.config().domain,
                                       ", and the vehicle's uXRCE-DDS client started with -n ", v.cfg.ns, "? ",
                                       discovery_hint(), ")"));
                return;
            case Step::await_estimator:
                // A real PX4's EKF2 needs seconds of visual odometry (yaw alignment, then position)
                // before it arms: asked sooner, it refused three times (issue 42). Past the timeout
                // the link asks anyway, so PX4's own refusal (and its reason) is what the operator sees.
                // A frame that must be tied to the floor (ground: estimate) is never armed untied.
                if (auto untied = untied_ground(v)) {
                    if (waited > o_.estimator_timeout_s)
                        refuse(v, log::cat("not armed: ", *untied, " after ", fixed(waited, 1),
                                           " s, so its frame cannot be tied to the lab's floor"));
                    return;
                }
                if (s.preflight_ok) return ask(v, Step::offboard, now, true);
                if (waited > o_.estimator_timeout_s) {
                    log::warn(v.cfg.name, ": PX4 system ", v.cfg.system_id, "'s pre-flight checks still fail after ",
                              waited, " s (no local position from its estimator yet?); asking for OFFBOARD anyway");
                    return ask(v, Step::offboard, now, true);
                }
                return;
            case Step::offboard:
                if (s.nav == px4::kNavOffboard) return ask(v, Step::arm, now, true);
                if (waited > o_.answer_timeout_s)
                    retry_or_refuse(v, now, "switch to OFFBOARD", px4::kCmdDoSetMode, offboard_hint(v, now));
                return;
            case Step::arm:
                if (s.arming == px4::kArmed && s.nav != px4::kNavOffboard)
                    return refuse(v, log::cat("PX4 (system ", v.cfg.system_id, ") armed but left OFFBOARD for ",
                                              px4::nav_state_name(s.nav), s.failsafe ? " (failsafe)" : ""));
                if (s.arming == px4::kArmed) {
                    v.step = Step::ready;
                    say_tie(v);
                    log::info(v.cfg.name, ": PX4 system ", v.cfg.system_id, " armed in OFFBOARD");
                    return;
                }
                if (waited > o_.answer_timeout_s)
                    retry_or_refuse(
                        v, now, "arm", px4::kCmdArmDisarm,
                        "its pre-arm checks failed (see QGroundControl or `commander check` on the PX4 console)");
                return;
            case Step::ready:
            case Step::refused: return;
        }
    }

    // What PX4's Agent must announce for this lab's profile to hear it (docs/OPERATOR.md, PX4 SITL).
    std::string discovery_hint() const {
        if (p_.config().profile == dds::Profile::local)
            return "The lab's local profile hears only 127.0.0.1: on the Agent's host, set PX4's UXRCE_DDS_PTCFG 1 "
                   "(localhost) and restart its uxrce_dds_client";
        return "With UXRCE_DDS_PTCFG 1 (localhost) PX4 is heard only by the local profile: keep it 0 for this "
               "profile";
    }

    // ground: estimate — why vehicle v's frame is not tied to the floor yet (nullopt: it is, or
    // the file places it).
    std::optional<std::string> untied_ground(Vehicle& v) {
        if (o_.ground != GroundFrom::estimate) return std::nullopt;
        std::lock_guard lock(mutex_);
        if (v.tie.tied()) return std::nullopt;
        return v.tie.describe();
    }

    // The tie as it stands when the vehicle arms: what the lab flies on.
    void say_tie(Vehicle& v) {
        if (o_.ground != GroundFrom::estimate) return;
        std::lock_guard lock(mutex_);
        log::info(v.cfg.name, ": at arming, ", v.tie.describe());
    }

    void await_estimator(Vehicle& v, Nanos now) {
        v.step = Step::await_estimator;
        v.step_since = now;
        log::info(
            v.cfg.name, ": waiting for PX4 system ", v.cfg.system_id, "'s pre-flight checks (its estimator's ",
            o_.odometry == OdometryBy::off ? "local position from its own sensors"
                                           : "local position from the visual odometry",
            o_.ground == GroundFrom::estimate ? ", and its estimate still on the ground to tie it to the floor)" : ")");
    }

    // Sends the command of `step` (a first try when `first`).
    void ask(Vehicle& v, Step step, Nanos now, bool first) {
        v.step = step;
        v.tries = first ? 1 : v.tries + 1;
        if (first) v.first_sent_ns = now;
        v.sent_ns = now;
        if (step == Step::offboard) command(v, px4::kCmdDoSetMode, px4::kModeFlagCustom, px4::kCustomMainModeOffboard);
        if (step == Step::arm) command(v, px4::kCmdArmDisarm, 1.0f, 0.0f);
    }

    void retry_or_refuse(Vehicle& v, Nanos now, const std::string& what, std::uint32_t cmd, const std::string& hint) {
        if (v.tries < o_.attempts) {
            log::warn(v.cfg.name, ": PX4 did not ", what, " within ", o_.answer_timeout_s, " s; asking again (",
                      v.tries + 1, " of ", o_.attempts, ")");
            return ask(v, v.step, now, false);
        }
        AckSeen a;
        {
            std::lock_guard lock(mutex_);
            a = v.last_ack;
        }
        const bool answered = a.command == cmd && a.seen_ns >= v.first_sent_ns;  // an answer to this step
        const auto accepted = static_cast<std::uint8_t>(px4::AckResult::accepted),
                   in_progress = static_cast<std::uint8_t>(px4::AckResult::in_progress);
        if (answered && a.result != accepted && a.result != in_progress)
            return refuse(v, log::cat("PX4 (system ", v.cfg.system_id, ") refused to ", what, ": ",
                                      px4::ack_result_name(a.result), " after ", v.tries, " tries; ", hint));
        if (answered)
            return refuse(v, log::cat("PX4 (system ", v.cfg.system_id, ") answered ", px4::ack_result_name(a.result),
                                      " to ", what, " but vehicle_status never showed it after ", v.tries, " tries"));
        refuse(v, log::cat("no answer from PX4 system ", v.cfg.system_id, " to ", what, " after ", v.tries,
                           " tries (is its MAV_SYS_ID ", v.cfg.system_id, "? PX4 ignores commands for another system",
                           v.ack->matched() == 0 ? unbridged_ack() : "", ")"));
    }

    // Why PX4 may refuse OFFBOARD: what the link itself knows it has not sent (a local position through
    // visual odometry, a setpoint stream of more than a second), or else PX4's side of it.
    std::string offboard_hint(Vehicle& v, Nanos now) {
        std::string missing;
        const auto add = [&](const std::string& what) { missing += (missing.empty() ? "" : "; ") + what; };
        const Nanos odom = odometry_ ? odometry_->last_sent_ns(v.cfg.name) : 0;
        if (o_.odometry == OdometryBy::off)
            add("no local position from the link (odometry: off, so PX4's estimator needs another source)");
        else if (o_.odometry == OdometryBy::bridge)
            add("no local position from the link (odometry: bridge: is dw-mocap-bridge running with --feed-px4?)");
        else if (odom == 0 || to_seconds(now - odom) > kOdometryGapS)
            add(log::cat("no local position from the link: no vehicle_visual_odometry sent ",
                         odom == 0 ? std::string("yet") : log::cat("for ", to_seconds(now - odom), " s"), " (is ",
                         v.cfg.name, " tracked by the motion capture?)"));
        if (v.stream_last_ns == 0 || to_seconds(now - v.stream_last_ns) > kStreamGapS)
            add("no setpoint stream from the planner (PX4 wants offboard_control_mode at more than 2 Hz)");
        else if (const double ran = std::max(0.0, to_seconds(v.first_sent_ns - v.stream_since_ns));
                 ran < kStreamWarmupS)
            add(log::cat("the setpoint stream had run ", ran, " s when OFFBOARD was asked (PX4 wants more than ",
                         kStreamWarmupS, " s)"));
        if (!missing.empty()) return missing;
        return "the link sent visual odometry and a setpoint stream, so PX4's estimator did not give a local position "
               "from them (EKF2_EV_CTRL, docs/OPERATOR.md) or they do not reach it";
    }

    // Why no answer could be heard: PX4 1.14 keeps its acks on the vehicle by default.
    std::string unbridged_ack() const {
        const auto& version = dds::px4_version(o_.version);
        if (version.ack_bridged) return "; or its vehicle_command_ack is not bridged";
        return log::cat("; PX4 ", version.name,
                        " does not bridge vehicle_command_ack unless its dds_topics.yaml adds it, so a refusal's "
                        "reason is only on the vehicle (QGroundControl, the PX4 console)");
    }

    // fmu/out/vehicle_odometry (PX4's default dds_topics.yaml bridges it): PX4's estimate, for the
    // descent's gate. A pose in another frame than NED, or one that is no pose (not finite, beyond
    // the room's plausible bounds: physics/plausible.hpp), is not used — dropped, counted, said once;
    // a velocity that is not usable cannot show the vehicle at rest, so that sample does not tie
    // the ground.
    void add_estimate_reader(Vehicle& v) {
        using Odometry = px4_msgs::msg::dds_::VehicleOdometry_;
        v.odometry_name = dds::px4_topic(v.cfg.ns, "out", "vehicle_odometry");
        Vehicle* vp = &v;
        v.odometry = std::make_unique<dds::Reader<Odometry>>(
            p_, dds::px4_topic_spec<Odometry>(v.odometry_name, "px4_msgs::msg::dds_::VehicleOdometry_"),
            [this, vp](const Odometry& m, const dds::SampleMeta&) {
                const physics::Vec3 local(m.position()[0], m.position()[1], m.position()[2]),
                    vel(m.velocity()[0], m.velocity()[1], m.velocity()[2]);
                if (m.pose_frame() != px4::kFrameNed) return;
                if (!physics::plausible_position(local)) {
                    if (vp->absurd_odometry.fetch_add(1) == 0)
                        log::warn(vp->cfg.name, ": ", vp->odometry_name,
                                  " gave a position that is no pose (not finite or beyond ",
                                  physics::kMaxPlausiblePositionM, " m): dropped (the first; counted)");
                    return;
                }
                std::lock_guard lock(mutex_);
                const Nanos now = p_.clock().monotonic_ns();
                if (o_.ground == GroundFrom::estimate && usable_velocity(vel)) {  // only while PX4 says disarmed
                    const bool was = vp->tie.tied();
                    vp->tie.add(to_seconds(now), local, vel, vp->st.seen_ns != 0 && vp->st.arming != px4::kArmed);
                    if (vp->tie.tied()) vp->frame.origin.z() = -*vp->tie.floor_d();
                    if (vp->tie.tied() && !was) log::info(vp->cfg.name, ": ", vp->tie.describe());
                }
                vp->estimate = {vp->frame.lab_point(local).z(), now};
            });
    }

    LocalFrame frame_of(const Vehicle& v) {
        std::lock_guard lock(mutex_);
        return v.frame;
    }

    static std::vector<std::string> names_of(const Px4Options& o) {
        std::vector<std::string> out;
        for (const auto& v : o.vehicles) out.push_back(v.name);
        return out;
    }

    void refuse(Vehicle& v, const std::string& why) {
        v.step = Step::refused;
        v.refusal = why;
    }

    dds::Participant& p_;
    Px4Options o_;
    std::mutex mutex_;
    std::deque<Vehicle> vehicles_;  // stable addresses: callbacks and specs refer to them
    std::map<std::string, Vehicle*> by_name_;
    std::unique_ptr<Px4OdometryFeed> odometry_;  // odometry: planner
    SetpointWriter record_;
    std::string run_id_;
    dds::Writer<msg::VehicleCommandSent> commands_;  // each command as sent, for the recording
};

}  // namespace

std::unique_ptr<VehicleLink> make_px4_link(dds::Participant& p, const Px4Options& o, const std::string& run_id) {
    if (o.version == dds::Px4Version::v1_14) return std::make_unique<Px4Link<Types114>>(p, o, run_id);
    if (o.version == dds::Px4Version::v1_16) return std::make_unique<Px4Link<Types116>>(p, o, run_id);
    return std::make_unique<Px4Link<Types115>>(p, o, run_id);
}

}  // namespace dw::planner
