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
#include "physics/stand.hpp"
#include "physics/wrench_model.hpp"
#include "stand_agent/agent.hpp"

namespace dw::stand {

// Forces on the 8 load cells from the physics of the neighbours on the mocap topic.
class PhysicsSource {
public:
    PhysicsSource(dds::Participant& p, const physics::PhysicsConfig& physics, std::string sufferer = flight::kSufferer);
    double force(int chip, Nanos t);  // callable from the bank (any thread)

private:
    physics::WrenchModel model_;
    physics::StandModel stand_;
    std::string sufferer_name_;
    std::mutex mutex_;
    physics::Vec3 sufferer_;
    std::vector<physics::Producer> producers_;
    dds::Reader<msg::MocapFrame> reader_;
};

struct RunOptions {
    bool realtime = false;  // SCHED_FIFO + mlockall for the sampling thread
    std::stop_token stop;   // sampling ends when it is requested
};

// Samples until o.stop is requested. Returns the number of wrench samples published.
std::uint64_t run_agent(dds::Participant& p, Hx711Driver& driver, StandAgent& agent, const RunOptions& o);

}  // namespace dw::stand
