#pragma once
// The supervised experiment over DDS: wait for the stand agent, the mocap bridge, the recorder
// (heartbeats) and the vehicles (mocap) -> CALIBRATE the stand -> take off -> fly the legs
// (setpoints at >= 50 Hz) -> land -> DONE. Experiment state (phase, leg, progress) is latched.
// Aborts safely — hold, then land — on mocap loss, a tracking error, a geofence breach, a lost
// participant (not back within the rejoin grace: a restarted recorder may be) or an operator's
// ABORT; the reason is published and logged.
#include <atomic>
#include <functional>
#include <map>
#include <mutex>
#include <stop_token>
#include <string>

#include "dds/heartbeat.hpp"
#include "swarm_planner/plan.hpp"
#include "swarm_planner/vehicle_link.hpp"

namespace dw::planner {

inline constexpr Range kRejoinGraceRange{0, 60, "s"};
// --tracking-bound and --takeoff-time (issue 42: a real PX4's take-off, with its spool-up and ramp,
// needs more time and room than the simulated vehicles).
inline constexpr Range kTrackingBoundRange{0.05, 5, "m"};
inline constexpr Range kTakeoffTimeRange{1, 60, "s"};
inline constexpr Range kTakeoffSettleRange{0, 120, "s"};
// A vehicle counts as airborne once the pose source measures it this far above the floor.
inline constexpr double kAirborneHeight_m = 0.15;

struct RunOptions {
    std::vector<std::string> wait_for{"stand_agent", "mocap_bridge", "recorder"};
    double wait_timeout_s = 30;
    double setpoint_hz = 50;
    double calibrate_s = 1.5;
    double takeoff_s = 4;  // the take-off curve, parked to the first setpoint
    // After the take-off curve, the longest the vehicles may take to reach their first setpoints
    // (a PX4 spools up and climbs on its ramp first); the tracking bound holds for each from then.
    double takeoff_settle_s = 10;
    double land_s = 4;
    double hold_s = 1;
    double mocap_timeout_s = 0.2;
    double tracking_error_m = 0.3;                      // in flight, farther than this from the setpoint aborts
    std::string tracking_bound_source = "the default";  // where it came from, for the abort's words
    double rejoin_grace_s = 0;                          // a required process lost aborts unless it is back within this
    std::string run_id;
    LinkKind link = LinkKind::sim;
    Px4Options px4;        // --vehicles px4: per-vehicle settings (none: the defaults)
    std::stop_token stop;  // a stop request: ABORTED, every vehicle landed
};

class Experiment {
public:
    Experiment(dds::Participant& p, const Plan& plan, const RunOptions& o);
    // Runs to DONE or ABORTED; returns the final phase. `reason()` says why it aborted.
    msg::ExperimentPhase run();
    const std::string& reason() const { return reason_; }
    int legs_flown() const { return legs_flown_; }

private:
    struct VehicleSeen {
        physics::Vec3 position = physics::Vec3::Zero();
        Nanos seen_ns = 0;
        bool tracking = false;
        std::uint64_t implausible = 0;  // states dropped as garbage (physics::plausible_position)
    };
    void publish_state(msg::ExperimentPhase phase, int leg, double progress, const std::string& message);
    // Sends the setpoints unless one is not finite: then nothing is sent and the reason returned.
    std::optional<std::string> send(const std::vector<physics::Setpoint>& sps);
    std::optional<std::string> fault(const std::vector<physics::Setpoint>& sps);
    // The tracking bound of vehicle i at error `err`: why it is broken, if so. A vehicle is held to it
    // from when it first meets it under position control (PX4: airborne, its take-off ramp over).
    std::optional<std::string> tracking_fault(std::size_t i, double err);
    // Vehicle i's height above the floor by the pose source (under mutex_); nullopt: not tracked.
    std::optional<double> height_of(std::size_t i);
    // Airborne by evidence (issue 69): not until the poses put it kAirborneHeight_m above the floor,
    // whatever PX4's land detector says (under mutex_).
    bool on_the_ground(std::size_t i);
    // After the take-off curve: holds the first setpoints until every vehicle meets the tracking
    // bound, at most takeoff_settle_s; else why not.
    std::optional<std::string> settle(const std::vector<physics::Setpoint>& first);
    // Flies `target(t)` for `duration` at the setpoint rate; stops early on a fault (returned).
    std::optional<std::string> fly(double duration, const std::function<std::vector<physics::Setpoint>(double)>& target,
                                   msg::ExperimentPhase phase, bool supervise);
    void land_safely(const std::string& why);
    // After the link's land(): waits (bounded by the link's land timeout) until it confirms every
    // vehicle landed; returns who is not, and for how long it was waited for.
    std::optional<std::string> confirm_landed();
    // Holds the parked setpoints while the link arms the vehicles; the refusal if it refuses.
    std::optional<std::string> arm_vehicles(const std::vector<physics::Setpoint>& hold);
    // ABORTED before take-off, with the reason (published and kept).
    msg::ExperimentPhase abort_on_ground(const std::string& why);
    // Waits (the wait timeout) until the motion capture tracks every vehicle and fills `parked`
    // with their poses; else why not.
    std::optional<std::string> find_parked(std::vector<physics::Vec3>& parked);
    // Tares the stand at hover thrust while the vehicles hold.
    void calibrate(const std::vector<physics::Setpoint>& hold);

    dds::Participant& p_;
    Plan plan_;
    RunOptions o_;
    dds::Writer<msg::ExperimentState> state_;
    dds::Writer<msg::ExperimentPlan> plan_writer_;
    dds::Writer<msg::ExperimentCommand> commands_;
    std::unique_ptr<VehicleLink> link_;
    std::mutex mutex_;
    std::map<std::string, VehicleSeen> seen_;
    struct Lost {
        Nanos since = 0;
        std::string reason;
    };
    std::map<std::string, Lost> lost_;  // required processes gone, until they return
    std::atomic<bool> abort_requested_{false};
    std::string abort_reason_;
    dds::Reader<msg::VehicleState> states_;
    dds::Reader<msg::ExperimentCommand> operator_;
    dds::PeerMonitor peers_;
    std::string reason_;
    int legs_flown_ = 0;
    int leg_ = -1;
    std::vector<physics::Setpoint> last_;
    std::vector<bool> held_;  // per vehicle: under the tracking bound (since take-off, once it met it)
};

}  // namespace dw::planner
