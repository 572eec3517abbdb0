#pragma once
// The stand agent on DDS: samples the bank, publishes raw frames, the wrench and the (latched)
// status; tares on the CALIBRATE experiment command. In simulation the emulated bank's load
// cells feel the physics of the neighbours seen on the mocap topic.
#include <atomic>
#include <functional>
#include <mutex>
#include <stop_token>
#include <vector>

#include "dds/endpoint.hpp"
#include "flight/flight.hpp"
#include "physics/recording_chain.hpp"
#include "physics/stand.hpp"
#include "physics/wrench_model.hpp"
#include "stand_agent/agent.hpp"

namespace dw::stand {

// Forces on the 8 load cells from the physics of the neighbours on the mocap topic, through the
// recording chain's positions, sensor and calibration stages (physics/recording_chain.hpp: the
// neighbours' true positions are the reported ones less the motion capture's error; the load
// cells feel the sensor's reading, gain and crosstalk applied — linear, so the agent's tare and
// calibration carry them into its wrench as a stand's would). The clock stage is the agent's
// clock (sim_clock_delay_s); the recording stage (effect modules' on_recording) acts on a
// recorded wrench, which the cells cannot carry, and is not applied.
class PhysicsSource {
public:
    // `world`: the simulated world's time, the one the motion capture stamps its poses in (the
    // host's clock on one machine; not the agent's, whose error may be simulated).
    PhysicsSource(dds::Participant& p, const physics::PhysicsConfig& physics, const Clock& world,
                  std::string sufferer = flight::kSufferer);
    double force(int chip, Nanos t);  // callable from the bank (any thread); t: the world's monotonic time
    // How far behind the poses it is given the simulated air acted since the last call, mean [s]:
    // a conversion's time less the capture stamp of the latest mocap frame (the motion capture's
    // latency, the transit, the frame's hold). A real stand has no such lag. < 0: no conversion yet.
    double take_air_lag_s();
    // Mocap frames refused for a stamp off the frames' own time (StampGate: garbled or forged).
    std::uint64_t stray_stamps() const;
    std::string summary() const;  // "; N mocap frames refused ...", for the agent's last line

private:
    physics::PhysicsConfig physics_;  // before the chain, which reads its effects
    physics::RecordingChain chain_;
    physics::RecordingChain::Live live_;
    physics::Vec3 position_error_;
    physics::WrenchModel model_;
    physics::StandModel stand_;
    std::string sufferer_name_;
    const Clock& world_;
    mutable std::mutex mutex_;
    StampGate stamps_;
    Nanos pose_stamp_ns_ = 0;  // the latest mocap frame's capture stamp (world realtime)
    double lag_sum_s_ = 0;
    std::size_t lag_n_ = 0;
    physics::Vec3 sufferer_;
    std::vector<physics::Producer> producers_;
    dds::Reader<msg::MocapFrame> reader_;
};

// How late a simulated stand stamps its wrench (the recording chain's clock stage): its agent's
// clock runs this much ahead of the lab's.
double sim_clock_delay_s(const physics::PhysicsConfig& physics);

struct RunOptions {
    bool realtime = false;  // SCHED_FIFO + mlockall for the sampling thread
    std::stop_token stop;   // sampling ends when it is requested
    // The stand's pipeline delay for its status (StandStatus.pipeline_delay_s), where it is
    // measured: a simulated stand's PhysicsSource::take_air_lag_s. Unset: not measured.
    std::function<double()> pipeline_delay_s;
};

// Samples until o.stop is requested. Returns the number of wrench samples published.
std::uint64_t run_agent(dds::Participant& p, Hx711Driver& driver, StandAgent& agent, const RunOptions& o);

}  // namespace dw::stand
