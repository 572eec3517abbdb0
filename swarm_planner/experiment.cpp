#include "swarm_planner/experiment.hpp"

#include <cmath>
#include <thread>

#include "core/log.hpp"
#include "core/numbers.hpp"
#include "dds/wire_enums.hpp"
#include "dds/time.hpp"

namespace dw::planner {
namespace {
// The last state (DONE or ABORTED) is written just before the process exits: the writer waits this
// long for every reader to acknowledge it, or it can die with the process unseen.
constexpr auto kFinalStateAckTimeout = std::chrono::seconds(2);

physics::Setpoint min_jerk(const physics::Vec3& a, const physics::Vec3& b, double t, double T) {
    const double s = std::clamp(t / T, 0.0, 1.0);
    physics::Setpoint sp;
    sp.position = a + (b - a) * (10 * std::pow(s, 3) - 15 * std::pow(s, 4) + 6 * std::pow(s, 5));
    sp.velocity = (b - a) / T * (30 * s * s - 60 * std::pow(s, 3) + 30 * std::pow(s, 4));
    return sp;
}

// The plan as a DDS message (latched, for the recorder and everyone else).
msg::ExperimentPlan plan_message(const Plan& plan, const std::string& run_id) {
    msg::ExperimentPlan pm;
    pm.header().run_id(run_id);
    pm.name(run_id);
    pm.formation(plan.formation.meta_name);
    pm.vehicles(plan.vehicles);
    for (const auto& off : plan.formation.offsets) {
        msg::Vector3 v;
        v.x(off.x());
        v.y(off.y());
        v.z(off.z());
        pm.offsets_m().push_back(v);
    }
    for (const auto& l : plan.reference.legs()) {
        msg::Leg leg;
        leg.index(static_cast<std::uint32_t>(l.index));
        const auto a = plan.reference.at(l.t_start).position, b = plan.reference.at(l.t_end).position;
        leg.start_m().x(a.x());
        leg.start_m().y(a.y());
        leg.start_m().z(a.z());
        leg.end_m().x(b.x());
        leg.end_m().y(b.y());
        leg.end_m().z(b.z());
        leg.speed_mps(plan.options.grid.speed_mps);
        leg.relative_altitude_m(l.altitude_m);
        pm.legs().push_back(leg);
    }
    pm.document(to_document(plan, false));
    return pm;
}

// Paces a fixed-rate loop (the setpoint stream) without drift: each wait ends one period after the last.
class Ticker {
public:
    explicit Ticker(double hz)
        : period_(
              std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(1.0 / hz))),
          next_(std::chrono::steady_clock::now()) {}
    void wait() {
        next_ += period_;
        std::this_thread::sleep_until(next_);
    }

private:
    std::chrono::steady_clock::duration period_;
    std::chrono::steady_clock::time_point next_;
};

}  // namespace

Experiment::Experiment(dds::Participant& p, const Plan& plan, const RunOptions& o)
    : p_(p),
      plan_(plan),
      o_(o),
      state_(p, dds::topics::experiment_state),
      plan_writer_(p, dds::topics::experiment_plan),
      commands_(p, dds::topics::experiment_command),
      states_(p, dds::topics::vehicle_state,
              [this](const msg::VehicleState& s, const dds::SampleMeta&) {
                  // Only the plan's vehicles: a name invented every sample must not grow seen_.
                  if (std::find(plan_.vehicles.begin(), plan_.vehicles.end(), s.vehicle_id()) == plan_.vehicles.end())
                      return;
                  std::lock_guard lock(mutex_);
                  auto& v = seen_[s.vehicle_id()];
                  const physics::Vec3 x(s.position_m().x(), s.position_m().y(), s.position_m().z());
                  // Garbage (NaN, 1e300) is no measurement (issue 70): dropped, counted; the last pose
                  // stands and ages, so a vehicle sending only garbage is "mocap lost" in time.
                  if (!physics::plausible_position(x)) {
                      if (v.implausible++ == 0)
                          log::warn(s.vehicle_id(), ": a vehicle state at ", x.transpose(),
                                    " is no measurement: dropped (so are any more)");
                      return;
                  }
                  v.tracking = s.tracking_valid();
                  if (v.tracking) {
                      v.position = x;
                      v.seen_ns = p_.clock().monotonic_ns();
                  }
              }),
      operator_(p, dds::topics::experiment_command,
                [this](const msg::ExperimentCommand& c, const dds::SampleMeta&) {
                    if (c.kind() == msg::CMD_ABORT || c.kind() == msg::CMD_STOP) {
                        std::lock_guard lock(mutex_);
                        abort_reason_ = log::cat("operator ", dds::command_name(c.kind()), " from ", c.issuer(),
                                                 c.reason().empty() ? "" : ": " + c.reason());
                        abort_requested_ = true;
                    }
                }),
      peers_(p, [this](const dds::PeerEvent& e) {
          if (std::find(o_.wait_for.begin(), o_.wait_for.end(), e.process) == o_.wait_for.end()) return;
          std::lock_guard lock(mutex_);
          if (e.kind == dds::PeerEvent::Kind::lost) {
              lost_.try_emplace(e.process, Lost{p_.clock().monotonic_ns(), e.reason});
              if (o_.rejoin_grace_s > 0)
                  log::warn("lost ", e.process, " (", e.reason, "): aborting unless it is back within ",
                            o_.rejoin_grace_s, " s");
          } else if (lost_.erase(e.process) > 0) {
              log::info(e.process, " is back");
          }
      }) {
    if (o_.run_id.empty()) o_.run_id = log::cat("run-", p.clock().now_ns() / kNanosPerSecond);
    if (o_.px4.vehicles.empty()) o_.px4 = default_px4_options(plan_.vehicles);
    link_ = make_link(o_.link, p, plan_.vehicles, o_.run_id, o_.px4);
    link_->set_fence(plan_.options.fence);  // the last gate: nothing outside the room reaches a vehicle
}

void Experiment::publish_state(msg::ExperimentPhase phase, int leg, double progress, const std::string& message) {
    msg::ExperimentState s;
    s.header().stamp(dds::to_msg(p_.clock().now_ns()));
    s.header().run_id(o_.run_id);
    s.phase(phase);
    s.leg_index(leg);
    s.leg_count(static_cast<std::uint32_t>(plan_.reference.legs().size()));
    s.progress(progress);
    s.eta_s(-1);
    s.message(message);
    state_.write(s);
    if (phase == msg::PHASE_DONE || phase == msg::PHASE_ABORTED) state_.wait_for_acknowledgments(kFinalStateAckTimeout);
}

std::optional<std::string> Experiment::send(const std::vector<physics::Setpoint>& sps) {
    for (std::size_t i = 0; i < sps.size(); ++i) {
        // Never reaches a vehicle: the last finite setpoints are held instead.
        if (!is_finite(sps[i])) return log::cat("non-finite setpoint for ", plan_.vehicles[i], " refused");
    }
    last_ = sps;
    link_->send(sps, p_.clock().now_ns());
    return std::nullopt;
}

std::optional<std::string> Experiment::fault(const std::vector<physics::Setpoint>& sps) {
    std::lock_guard lock(mutex_);
    if (abort_requested_) return abort_reason_;
    if (auto f = link_->failsafe()) return f;
    const Nanos now = p_.clock().monotonic_ns();
    for (const auto& [process, lost] : lost_)
        if (!(to_seconds(now - lost.since) < o_.rejoin_grace_s))
            return log::cat("lost participant ", process, " (", lost.reason, ")");
    // Each check passes only when positively satisfied: a NaN anywhere is a fault.
    for (std::size_t i = 0; i < sps.size(); ++i) {
        const auto it = seen_.find(plan_.vehicles[i]);
        const double age = it == seen_.end() ? 1e9 : to_seconds(now - it->second.seen_ns);
        if (!(age <= o_.mocap_timeout_s))
            return log::cat("mocap lost: no pose of ", plan_.vehicles[i], " for ", age > 1e8 ? 0.0 : age, " s");
        const auto& x = it->second.position;
        if (!plan_.options.fence.holds_measured(x)) {
            return log::cat("geofence breach by ", plan_.vehicles[i], " at (", x.x(), ", ", x.y(), ", ", x.z(), ")");
        }
        if (auto f = tracking_fault(i, (x - sps[i].position).norm())) return f;
    }
    return std::nullopt;
}

std::optional<std::string> Experiment::tracking_fault(std::size_t i, double err) {
    if (i >= held_.size()) held_.resize(plan_.vehicles.size(), true);
    if (!held_[i]) {
        std::string how;
        held_[i] = err <= o_.tracking_error_m && link_->following(i, how) && !on_the_ground(i);
        return std::nullopt;
    }
    if (!(err <= o_.tracking_error_m))
        return log::cat("tracking error of ", plan_.vehicles[i], ": ", err, " m from its setpoint (bound ",
                        o_.tracking_error_m, " m, ", o_.tracking_bound_source, ")");
    return std::nullopt;
}

std::optional<double> Experiment::height_of(std::size_t i) {
    const auto it = seen_.find(plan_.vehicles[i]);
    if (it == seen_.end() || !it->second.tracking) return std::nullopt;
    return -it->second.position.z();
}

bool Experiment::on_the_ground(std::size_t i) {
    const auto h = height_of(i);
    return !h || !(*h >= kAirborneHeight_m);
}

std::optional<std::string> Experiment::settle(const std::vector<physics::Setpoint>& first) {
    const auto start = std::chrono::steady_clock::now();
    Ticker ticker(o_.setpoint_hz);
    for (;;) {
        if (o_.stop.stop_requested()) return std::string("interrupted (SIGINT/SIGTERM)");
        if (auto refused = send(first)) return refused;
        if (auto f = fault(first)) return f;
        std::vector<std::string> lagging;
        for (std::size_t i = 0; i < first.size(); ++i) {
            std::string how;
            if (held_[i]) continue;
            const bool follows = link_->following(i, how);
            std::lock_guard lock(mutex_);
            if (follows && on_the_ground(i))  // airborne by evidence: the pose source's, not PX4's word
                how = log::cat("on the ground by the poses: ", fixed(height_of(i).value_or(0.0), 2),
                               " m above the floor, though the link says it flies");
            else if (follows) how = "farther than the bound";
            lagging.push_back(log::cat(plan_.vehicles[i], " (", how, ")"));
        }
        if (lagging.empty()) return std::nullopt;
        const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (waited >= o_.takeoff_settle_s)
            return log::cat("take-off not completed ", fixed(waited, 1),
                            " s after the take-off curve: ", log::join(lagging), " (tracking bound ",
                            o_.tracking_error_m, " m, ", o_.tracking_bound_source, ")");
        ticker.wait();
    }
}

std::optional<std::string> Experiment::fly(double duration,
                                           const std::function<std::vector<physics::Setpoint>(double)>& target,
                                           msg::ExperimentPhase phase, bool supervise) {
    const auto start = std::chrono::steady_clock::now();
    Ticker ticker(o_.setpoint_hz);
    int last_report = -1;
    for (;;) {
        const double t = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (!(t <= duration)) break;
        if (o_.stop.stop_requested() && supervise) return std::string("interrupted (SIGINT/SIGTERM)");
        const auto sps = target(t);
        if (auto refused = send(sps)) {
            if (supervise) return refused;
            link_->send(last_, p_.clock().now_ns());  // landing: hold the last finite setpoints
        }
        if (supervise && t > 0.3) {  // the vehicles need a moment to start following
            if (auto f = fault(sps)) return f;
        }
        if (phase == msg::PHASE_FLYING) {
            int leg = -1;
            for (const auto& l : plan_.reference.legs()) {
                if (t >= l.t_start) leg = l.index;
                if (t >= l.t_end) legs_flown_ = std::max(legs_flown_, l.index + 1);
            }
            leg_ = leg;
        }
        const int report = static_cast<int>(t * 2);  // the latched state twice a second
        if (report != last_report) {
            publish_state(phase, leg_, phase == msg::PHASE_FLYING ? t / plan_.duration_s() : 0.0,
                          dds::phase_name(phase));
            last_report = report;
        }
        ticker.wait();
    }
    return send(target(duration));  // end exactly where the segment ends
}

void Experiment::land_safely(const std::string& why) {
    log::error("ABORT: ", why);
    reason_ = why;
    publish_state(msg::PHASE_LANDING, leg_, 0, "aborting: " + why + " — holding, then landing");
    link_->begin_descent();  // from here on no vehicle is sent above where it is (VehicleLink)
    // In a take-off, PX4's climb ramp goes on whatever the setpoints say (a real SITL rose 0.7 m after
    // an abort held it): a vehicle not yet under the tracking bound is landed by PX4 at once.
    const bool taking_off = held_.size() < plan_.vehicles.size() ||
                            std::any_of(held_.begin(), held_.end(), [](bool held) { return !held; });
    if (taking_off) link_->land();
    const auto hold = last_;
    fly(
        o_.hold_s, [&](double) { return hold; }, msg::PHASE_LANDING, false);
    std::vector<physics::Vec3> from, to;
    for (const auto& s : hold) {
        from.push_back(s.position);
        to.push_back(physics::Vec3(s.position.x(), s.position.y(), 0.0));  // straight down to the floor
    }
    fly(
        o_.land_s,
        [&](double t) {
            std::vector<physics::Setpoint> sps;
            for (std::size_t i = 0; i < from.size(); ++i) sps.push_back(min_jerk(from[i], to[i], t, o_.land_s));
            return sps;
        },
        msg::PHASE_LANDING, false);
    link_->land();
    const auto up = confirm_landed();
    publish_state(msg::PHASE_ABORTED, leg_, 0,
                  "ABORTED: " + why + (up ? "; landing NOT confirmed: " + *up : "; every vehicle landed"));
}

std::optional<std::string> Experiment::confirm_landed() {
    const auto start = std::chrono::steady_clock::now();
    Ticker ticker(o_.setpoint_hz);
    for (;;) {
        const auto up = link_->still_flying();
        if (!up) return std::nullopt;
        const double waited = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (o_.stop.stop_requested()) return *up + " when stopped";
        if (waited >= link_->land_timeout_s()) return log::cat(*up, " after ", fixed(waited, 1), " s");
        ticker.wait();
    }
}

std::optional<std::string> Experiment::arm_vehicles(const std::vector<physics::Setpoint>& hold) {
    publish_state(msg::PHASE_TAKING_OFF, -1, 0, "arming");
    Ticker ticker(o_.setpoint_hz);
    for (;;) {  // bounded by the link's own attempts and timeouts
        if (o_.stop.stop_requested()) return std::string("interrupted (SIGINT/SIGTERM) while arming");
        send(hold);
        const ArmProgress a = link_->arm();
        if (a.state == ArmProgress::State::ready) return std::nullopt;
        if (a.state == ArmProgress::State::refused) return a.reason;
        ticker.wait();
    }
}

msg::ExperimentPhase Experiment::abort_on_ground(const std::string& why) {
    reason_ = why;
    publish_state(msg::PHASE_ABORTED, -1, 0, "ABORTED: " + reason_);
    return msg::PHASE_ABORTED;
}

std::optional<std::string> Experiment::find_parked(std::vector<physics::Vec3>& parked) {
    const std::size_t k = plan_.vehicles.size();
    // The vehicles' parked poses, from the motion capture, within the wait timeout.
    const auto deadline = std::chrono::steady_clock::now() + to_millis(o_.wait_timeout_s);
    while (!o_.stop.stop_requested()) {
        std::size_t n = 0;
        {
            std::lock_guard lock(mutex_);
            for (std::size_t v = 0; v < k; ++v) {
                auto it = seen_.find(plan_.vehicles[v]);
                if (it != seen_.end() && it->second.tracking) {
                    parked[v] = it->second.position;
                    ++n;
                }
            }
        }
        if (n == k || std::chrono::steady_clock::now() >= deadline) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    if (o_.stop.stop_requested()) return std::string("interrupted (SIGINT/SIGTERM) while waiting");
    std::lock_guard lock(mutex_);
    for (std::size_t v = 0; v < k; ++v) {
        const auto it = seen_.find(plan_.vehicles[v]);
        if (it == seen_.end() || !it->second.tracking)  // never take off from an unknown pose
            return "vehicle " + plan_.vehicles[v] + " is not seen by the motion capture";
        const physics::Vec3& x = it->second.position;  // nor from outside the room (issue 70)
        if (!plan_.options.fence.holds_measured(x))
            return log::cat("vehicle ", plan_.vehicles[v], " is parked outside the geofence, at (", x.x(), ", ", x.y(),
                            ", ", x.z(), "): no setpoint is sent to it");
        parked[v] = plan_.options.fence.on_floor(x);  // seen a little below the floor, it sits on it
    }
    return std::nullopt;
}

void Experiment::calibrate(const std::vector<physics::Setpoint>& hold) {
    publish_state(msg::PHASE_CALIBRATING, -1, 0, "CALIBRATE: stand tare at hover thrust");
    msg::ExperimentCommand c;
    c.kind(msg::CMD_CALIBRATE);
    c.issuer("planner");
    c.header().run_id(o_.run_id);
    commands_.write(c);
    fly(
        o_.calibrate_s, [&](double) { return hold; }, msg::PHASE_CALIBRATING, false);
}

msg::ExperimentPhase Experiment::run() {
    const std::size_t k = plan_.vehicles.size();
    // The plan, latched, for the recorder and everyone else.
    msg::ExperimentPlan pm = plan_message(plan_, o_.run_id);
    plan_writer_.write(pm);

    publish_state(msg::PHASE_WAITING, -1, 0,
                  "waiting for the stand agent, the mocap bridge, the recorder and the vehicles");
    log::info("waiting for ", o_.wait_for.size(), " processes and ", k, " vehicles");
    if (!peers_.wait_for(o_.wait_for, to_millis(o_.wait_timeout_s), o_.stop))
        return abort_on_ground(o_.stop.stop_requested() ? "interrupted (SIGINT/SIGTERM) while waiting"
                                                        : "not every participant came up within the wait timeout");
    std::vector<physics::Vec3> parked(k);
    if (auto why = find_parked(parked)) return abort_on_ground(*why);
    std::vector<physics::Setpoint> hold(k);
    for (std::size_t v = 0; v < k; ++v) hold[v].position = parked[v];
    calibrate(hold);

    auto takeoff = [&](double t) {
        std::vector<physics::Setpoint> sps;
        for (std::size_t v = 0; v < k; ++v)
            sps.push_back(min_jerk(parked[v], plan_.setpoint(v, 0).position, t, o_.takeoff_s));
        return sps;
    };
    if (auto refused = arm_vehicles(hold)) {
        link_->land();  // whatever did arm lands (on the ground: PX4 disarms)
        return abort_on_ground(*refused);
    }
    held_.assign(k, false);  // each vehicle is held to the tracking bound once it meets it
    auto f = fly(o_.takeoff_s, takeoff, msg::PHASE_TAKING_OFF, true);
    if (!f) f = settle(takeoff(o_.takeoff_s));
    if (f) {
        land_safely(*f);
        return msg::PHASE_ABORTED;
    }
    log::info("flying ", plan_.reference.legs().size(), " legs (", plan_.duration_s(), " s)");
    auto legs = [&](double t) {
        std::vector<physics::Setpoint> sps;
        for (std::size_t v = 0; v < k; ++v) sps.push_back(plan_.setpoint(v, t));
        return sps;
    };
    if (auto failed = fly(plan_.duration_s(), legs, msg::PHASE_FLYING, true)) {
        land_safely(*failed);
        return msg::PHASE_ABORTED;
    }
    legs_flown_ = static_cast<int>(plan_.reference.legs().size());
    link_->begin_descent();
    std::vector<physics::Vec3> from(k);
    for (std::size_t v = 0; v < k; ++v) from[v] = plan_.setpoint(v, plan_.duration_s()).position;
    fly(
        o_.land_s,
        [&](double t) {
            std::vector<physics::Setpoint> sps;
            for (std::size_t v = 0; v < k; ++v) sps.push_back(min_jerk(from[v], parked[v], t, o_.land_s));
            return sps;
        },
        msg::PHASE_LANDING, false);
    link_->land();
    if (const auto up = confirm_landed()) {  // the run is not over while a vehicle may still be flying
        reason_ = "landing not confirmed: " + *up;
        log::error(reason_);
        publish_state(msg::PHASE_ABORTED, leg_, 1.0, log::cat("ABORTED: ", legs_flown_, " legs flown; ", reason_));
        return msg::PHASE_ABORTED;
    }
    if (abort_requested_) {  // an abort during the landing: already going down, it goes on; the run says so
        {
            std::lock_guard lock(mutex_);
            reason_ = abort_reason_ + " during the landing (the landing went on)";
        }
        log::error("ABORT: ", reason_);
        publish_state(msg::PHASE_ABORTED, leg_, 1.0,
                      log::cat("ABORTED: ", reason_, "; ", legs_flown_, " legs flown; every vehicle landed"));
        return msg::PHASE_ABORTED;
    }
    publish_state(msg::PHASE_DONE, leg_, 1.0, log::cat("DONE: ", legs_flown_, " legs flown; every vehicle landed"));
    return msg::PHASE_DONE;
}

}  // namespace dw::planner
