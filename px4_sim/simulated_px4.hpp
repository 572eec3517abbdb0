#pragma once
// A simulated PX4 for the lab's tests and demos: PX4's uXRCE-DDS topics under its client's
// namespace, read and written as PX4 lays them out (px4_sim/wire.hpp, per version), with the
// Commander's rules the lab relies on:
// - a VehicleCommand for another system (target_system not MAV_SYS_ID nor 0) or component is
//   ignored: no answer at all;
// - OFFBOARD is refused (TEMPORARILY_REJECTED) without a fresh offboard_control_mode stream
//   (its timestamp within COM_OF_LOSS_T of this host's clock) that has lasted over 1 s, or
//   without a local position (vehicle_visual_odometry that EKF2 would accept, recently);
// - a local position only after EKF2's warm-up: with the vision source, visual odometry arriving
//   continuously for ekf_warmup_s (yaw alignment, then position); with the onboard source (GPS,
//   or SITL's ground truth) ekf_warmup_s after boot, no visual odometry needed;
//   vehicle_status.pre_flight_checks_pass is false until then, or while a pre-arm check fails;
// - its estimate on fmu/out/vehicle_odometry (NED, stamped as PX4's client stamps what it sends:
//   on the Agent host's clock) while it has a local position, as PX4's dds_topics.yaml bridges it;
// - arming is DENIED without a local position or when a pre-arm check fails;
// - in OFFBOARD, a stream older than COM_OF_LOSS_T is a failsafe: AUTO_LAND (COM_OBL_RC_ACT 4);
// - airborne on vision, a local position lost (no visual odometry for position_timeout_s) is a
//   failsafe: DESCEND, PX4's blind land;
// - landed in AUTO_LAND or DESCEND (its land detector: on the ground), it disarms after COM_DISARM_LAND;
// - take-off as mc_pos_control flies it: armed, the motors spool up (COM_SPOOLUP_TIME) and it stays
//   on the ground; then, once a setpoint asks it up, it climbs at a speed ramped from 0 to
//   MPC_TKO_SPEED over MPC_TKO_RAMP_T, with no horizontal control until the land detector sees it
//   airborne (vehicle_status.takeoff_time is then set); after the ramp it follows its setpoints.
// It also plays the vehicle and the motion capture: it follows the trajectory setpoints in its
// local frame and publishes its pose as the lab's vehicles/state (lab NED).
#include <atomic>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "dds/endpoint.hpp"
#include "dds/raw.hpp"
#include "px4_sim/wire.hpp"
#include "swarm_planner/px4_config.hpp"

namespace dw::px4sim {

// Where EKF2's position comes from: the lab's visual odometry (motion capture), or the vehicle's
// own sensors (GPS, optical flow, SITL's ground truth).
enum class PositionSource { vision, onboard };
inline constexpr const char* kPositionSourceNames[] = {"vision", "onboard"};  // PositionSource's values in order

inline constexpr double kOnboardOriginAboveFloor_m = 1.7;
inline constexpr double kOnboardWander_m = 0.1;
inline constexpr double kWanderPeriod_s = 20.0;
// PX4's time synchroniser (lib/timesync/Timesync.cpp) resets on a "time jump" and reconverges; a
// v1.15.4 SITL logged "time jump detected. Resetting time synchroniser." again and again. These
// are the double's: a reset this often, unsynchronised this long (chosen, not measured).
inline constexpr double kTimeJumpEvery_s = 12.0;
inline constexpr double kTimeResync_s = 3.0;

struct SimulatedPx4Options {
    dds::Px4Version version = dds::Px4Version::v1_15;
    std::string ns;                                // its client's -n ("" = rt/fmu/...)
    int system_id = 1;                             // MAV_SYS_ID
    std::string vehicle = "v1";                    // its name in the lab (vehicles/state)
    planner::LocalFrame frame;                     // where its local frame sits in the lab
    physics::Vec3 parked = physics::Vec3::Zero();  // lab NED, on the ground
    double com_of_loss_t_s = 1.0;                  // COM_OF_LOSS_T
    double offboard_warmup_s = 1.0;                // the stream's age before OFFBOARD is accepted
    double position_timeout_s = 0.5;               // visual odometry older than this: no local position
    double ekf_warmup_s = 3.0;                     // EKF2: continuous odometry this long before a local position
    PositionSource position_source = PositionSource::vision;
    // Issue 69: a PX4 on its own sensors (a v1.15.4 SITL) has its local origin where GPS and barometer
    // put it, metres off the floor, and its estimate wanders. By default as PX4 does it: on the onboard
    // source, the origin kOnboardOriginAboveFloor_m above the floor and the estimate wandering by
    // kOnboardWander_m (D; half of it in N) over kWanderPeriod_s; on vision, neither.
    std::optional<double> origin_above_floor_m;
    std::optional<double> estimate_wander_m;
    // Its land detector says airborne as the take-off ramp starts while the vehicle never leaves the
    // ground (a v1.15.4 SITL's ground truth stayed on the ground while takeoff_time was set).
    bool land_detector_fooled = false;
    // Time jumps: every time_jump_every_s (0: never) its synchroniser resets for time_resync_s. PX4's
    // client adds the synchroniser's offset to its outgoing timestamp and timestamp_sample and
    // subtracts it from incoming ones (clamped to now); while unsynchronised the offset is 0, so its
    // stamps are its boot time and whatever the lab stamps reads as now (Tools/msg/templates/ucdr).
    // takeoff_time is never adjusted: always boot time. On by default, as PX4 did.
    double time_jump_every_s = kTimeJumpEvery_s;
    double time_resync_s = kTimeResync_s;
    std::string refuse_arm;                       // non-empty: a pre-arm check that fails (arming DENIED)
    std::optional<double> lose_offboard_after_s;  // after arming it hears no more offboard stream
    std::optional<double> lose_vision_after_s;    // after arming no more visual odometry reaches its estimator
    std::optional<double> kill_after_s;           // after arming the kill switch is thrown (motors stop)
    double com_kill_disarm_s = 5.0;               // COM_KILL_DISARM: killed this long, PX4 disarms
    double com_disarm_land_s = 2.0;               // COM_DISARM_LAND: landed this long, PX4 disarms
    double com_spoolup_time_s = 1.0;              // COM_SPOOLUP_TIME: armed, the motors spool up this long
    double mpc_tko_ramp_t_s = 3.0;                // MPC_TKO_RAMP_T: the take-off's climb-speed ramp
    double mpc_tko_speed_mps = 1.5;               // MPC_TKO_SPEED: the take-off's climb speed
    std::optional<double> low_battery_after_s;    // after arming the battery reaches its failsafe level
    double rate_hz = 100;                         // dynamics and vehicles/state
    double status_period_s = 0.5;                 // vehicle_status (also on every change)
    bool publish_state = true;                    // vehicles/state (false: the motion capture is played elsewhere)
    bool reads_commands = true;  // false: the Agent does not bridge fmu/in/vehicle_command (a misconfigured Agent)
    // Whether it publishes vehicle_command_ack; default: as the version's dds_topics.yaml (1.14: no).
    std::optional<bool> publishes_ack;
};

class SimulatedPx4 {
public:
    // `lab`: the lab's participant (vehicles/state); `px4_side`: where PX4's Agent would be.
    SimulatedPx4(dds::Participant& lab, const dds::DdsConfig& px4_side, SimulatedPx4Options o);
    ~SimulatedPx4();
    SimulatedPx4(const SimulatedPx4&) = delete;
    SimulatedPx4& operator=(const SimulatedPx4&) = delete;

    struct Report {
        int ignored_commands = 0;   // for another system or component
        int undecodable = 0;        // payloads shorter than this version's definition
        int rejected_odometry = 0;  // samples EKF2 would drop
        bool was_offboard = false, was_armed = false, armed = false;
        bool local_position = false;  // its estimator has one now
        std::uint8_t nav_state = 0;
        std::vector<std::string> events;  // one line each: what it accepted, refused and why
    };
    Report report() const;
    // Where it is now, lab NED (what a motion capture would see).
    physics::Vec3 lab_position() const;

private:
    physics::Vec3 wander(Nanos mono) const;  // under mutex_
    double wander_m_ = 0;
    struct State;
    bool link_cut(Nanos mono) const;  // under mutex_
    bool synced(Nanos mono) const;    // its time synchroniser has converged (no time jump being recovered from)
    double stamp_out_us() const;      // an outgoing timestamp, as its client writes it
    std::uint64_t stamp_in_us(double stamp) const;  // an incoming one, as its modules read it (this host's realtime µs)
    std::uint64_t boot_us() const;                  // its own clock: µs since it booted
    bool local_position(Nanos mono) const;          // under mutex_: EKF2 has one (fresh odometry, warmed up)
    void on_mode(std::span<const std::uint8_t> b);
    void on_trajectory(std::span<const std::uint8_t> b);
    void on_odometry(std::span<const std::uint8_t> b);
    void on_command(std::span<const std::uint8_t> b);
    dds::px4::AckResult commander(const Values& cmd, std::string& why);  // under mutex_
    void loop(std::stop_token stop);
    void step(double dt);                                      // under mutex_
    void follow(double dt, Nanos mono);                        // under mutex_: in OFFBOARD, armed
    void faults(Nanos mono);                                   // under mutex_
    void disarm(std::uint8_t reason, const std::string& why);  // under mutex_
    void publish_status();
    void publish_estimate(const physics::Vec3& local_velocity);
    std::optional<Values> decode_or_count(Msg m, std::span<const std::uint8_t> b);
    void event(const std::string& line);  // under mutex_

    // Destroyed in reverse: the thread stops first, then PX4's endpoints (their callbacks use the
    // state), then the state.
    SimulatedPx4Options o_;
    dds::Participant& lab_;
    mutable std::mutex mutex_;
    std::unique_ptr<State> s_;
    std::unique_ptr<dds::Writer<msg::VehicleState>> states_;  // when o_.publish_state
    dds::RawParticipant px4_;
    std::jthread thread_;
};

}  // namespace dw::px4sim
