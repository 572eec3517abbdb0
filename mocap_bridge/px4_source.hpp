#pragma once
// Poses without motion capture: each PX4's own estimate (EKF2's fmu/out/vehicle_odometry, in its
// local NED) as the lab's poses, for a lab that flies on PX4's estimate (GPS, optical flow, or a
// simulated PX4). The planner's PX4 file places each local frame in the lab (origin, heading) and
// names each vehicle's namespace, as it does for the link. Published as the bridge publishes
// motion capture — mocap/frame (pose_source POSE_VEHICLE_ESTIMATE: the recording, and a flight
// exported from it, say the poses are estimates) and vehicles/state — with the sufferer where the
// stand holds it. Each frame holds every body's latest estimate carried to the frame's stamp by its
// estimated velocity; an estimate older than `stale_s` is not tracking.
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "dds/endpoint.hpp"
#include "dds/px4.hpp"
#include "physics/wrench_model.hpp"
#include "swarm_planner/ground_tie.hpp"
#include "swarm_planner/px4_status.hpp"
#include "swarm_planner/px4_config.hpp"

namespace dw::natnet {

inline constexpr Range kEstimateRateRange{1, 1000, "Hz"};

struct Px4SourceOptions {
    planner::Px4Options px4;                // namespaces, frames, version (the planner's --px4 file)
    std::optional<physics::Vec3> sufferer;  // lab NED: the sufferer held by the stand, one more body
    double rate_hz = 100;                   // frames published
    double stale_s = 0.5;                   // an older estimate is not tracking (EKF2 publishes at ~100 Hz)
};

class Px4PoseSource {
public:
    Px4PoseSource(dds::Participant& p, Px4SourceOptions o);
    struct Output {
        msg::MocapFrame frame;
        std::vector<msg::VehicleState> states;
    };
    // Every body's latest estimate at `now_ns` (the lab's clock).
    Output frame(Nanos now_ns);
    std::uint64_t received() const;
    std::uint64_t rejected() const;  // estimates not in NED or not finite
    const Px4SourceOptions& options() const { return o_; }

private:
    struct Estimate {
        physics::Vec3 position = physics::Vec3::Zero(), velocity = physics::Vec3::Zero();  // lab NED
        Eigen::Quaterniond attitude = Eigen::Quaterniond::Identity();                      // body -> lab NED
        Nanos captured_ns = 0;  // the lab's clock: received less the estimate's age at publication
    };
    struct Vehicle {
        planner::Px4Vehicle cfg;
        std::string topic;  // stable: the reader's spec views it
        std::optional<Estimate> latest;
        planner::GroundTie tie;  // px4.ground estimate: where its floor is
        bool tie_said = false;
        std::uint64_t untied = 0;  // estimates received before the tie
        std::unique_ptr<dds::Reader<px4_msgs::msg::dds_::VehicleOdometry_>> reader;
    };
    void on_odometry(Vehicle& v, const px4_msgs::msg::dds_::VehicleOdometry_& m);
    msg::VehicleState state_of(const Vehicle& v, const msg::RigidBody& body, Nanos now_ns) const;

    dds::Participant& p_;
    Px4SourceOptions o_;
    planner::Px4ArmedWatch armed_;  // ground: estimate ties only while disarmed
    mutable std::mutex mutex_;
    std::deque<Vehicle> vehicles_;  // stable addresses: the callbacks refer to them
    std::uint64_t frames_ = 0, received_ = 0, rejected_ = 0;
};

}  // namespace dw::natnet
