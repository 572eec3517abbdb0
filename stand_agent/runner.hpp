#pragma once
// The stand agent on DDS: samples the bank, publishes raw frames, the wrench and the (latched)
// status; tares on the CALIBRATE experiment command. In simulation the emulated bank's load
// cells feel the physics of the neighbours seen on the mocap topic.
#include <atomic>
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
    PhysicsSource(dds::Participant& p, const physics::PhysicsConfig& physics, std::string sufferer = flight::kSufferer);
    double force(int chip, Nanos t);  // callable from the bank (any thread)

private:
    physics::PhysicsConfig physics_;  // before the chain, which reads its effects
    physics::RecordingChain chain_;
    physics::RecordingChain::SensorStream sensor_;
    physics::Vec3 position_error_;
    physics::WrenchModel model_;
    physics::StandModel stand_;
    std::string sufferer_name_;
    std::mutex mutex_;
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
};

// Samples until o.stop is requested. Returns the number of wrench samples published.
std::uint64_t run_agent(dds::Participant& p, Hx711Driver& driver, StandAgent& agent, const RunOptions& o);

}  // namespace dw::stand
