#pragma once
// Whether each PX4 is armed, from its vehicle_status (the configured version's type and topic), for
// the processes that read PX4 without commanding it: the mocap bridge ties a PX4 frame to the floor
// only while PX4 says the vehicle is disarmed (swarm_planner/ground_tie.hpp), as the link does.
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "dds/endpoint.hpp"
#include "swarm_planner/px4_config.hpp"

namespace dw::planner {

class Px4ArmedWatch {
public:
    Px4ArmedWatch(dds::Participant& p, const Px4Options& o);
    // nullopt: no vehicle_status from it yet.
    std::optional<bool> armed(const std::string& vehicle) const;

private:
    template <class Status>
    void watch(dds::Participant& p, const Px4Vehicle& v, const std::string& topic);

    mutable std::mutex mutex_;
    std::map<std::string, bool> armed_;
    std::vector<std::string> topics_;             // stable: the specs view them
    std::vector<std::shared_ptr<void>> readers_;  // one per vehicle, of the version's status type
};

}  // namespace dw::planner
