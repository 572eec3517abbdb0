#pragma once
// The motion capture into each PX4's estimator: vehicle_visual_odometry (EKF2 fuses it, not
// vehicle_mocap_odometry) on rt/<ns>/fmu/in/, from the lab's vehicle states, in each vehicle's
// local NED (Px4Options' origin and heading), the quaternion w first and normalised in float as
// EKF2 checks it, the settings' variances, timestamp_sample = the capture time, at odometry_hz.
// A vehicle whose tracking comes back gets a new reset_counter (the estimator may see a jump).
// Used by the planner's PX4 link (`odometry: planner`: only while the planner runs) and by the
// mocap bridge (`dw-mocap-bridge --feed-px4`, `odometry: bridge`: whenever a vehicle is tracked,
// so that PX4's estimator has warmed up before anyone arms).
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "dds/endpoint.hpp"
#include "dds/px4.hpp"
#include "swarm_planner/px4_config.hpp"

namespace dw::planner {

class Px4OdometryFeed {
public:
    // `subscribe`: read the lab's vehicles/state itself; otherwise the owner calls on_state.
    Px4OdometryFeed(dds::Participant& p, const Px4Options& o, bool subscribe);
    void on_state(const msg::VehicleState& s);
    // When the named vehicle's last odometry was sent (monotonic; 0 = never).
    Nanos last_sent_ns(const std::string& vehicle) const;

private:
    struct Vehicle {
        LocalFrame frame;
        std::string topic;  // stable: the writer's spec views it
        std::unique_ptr<dds::Writer<px4_msgs::msg::dds_::VehicleOdometry_>> writer;
        Nanos sent_ns = 0;
        bool tracking = false;
        std::uint8_t reset_counter = 0;
    };
    px4_msgs::msg::dds_::VehicleOdometry_ odometry(const Vehicle& v, const msg::VehicleState& s) const;
    // Logs once the median capture-to-send latency (EKF2_EV_DELAY must hold it: a real PX4 replaced
    // the capture time it was sent with its receive time, issue 42).
    void note_latency(Nanos capture_to_send);

    dds::Participant& p_;
    Px4Options o_;
    mutable std::mutex mutex_;
    std::deque<Vehicle> vehicles_;  // stable addresses
    std::map<std::string, Vehicle*, std::less<>> by_name_;
    std::vector<double> latencies_ms_;
    std::uint64_t untimely_ = 0;  // states whose stamp is no time here (dds::stamp_in_time): not sent
    std::unique_ptr<dds::Reader<msg::VehicleState>> states_;  // last: its callback uses the rest
};

}  // namespace dw::planner
