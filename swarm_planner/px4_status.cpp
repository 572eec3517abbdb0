#include "swarm_planner/px4_status.hpp"

#include "dds/px4.hpp"

namespace dw::planner {

template <class Status>
void Px4ArmedWatch::watch(dds::Participant& p, const Px4Vehicle& v, const std::string& topic) {
    dds::QosOverrides latest;  // PX4's fmu/out writers are TRANSIENT_LOCAL
    latest.transient_local = true;
    const std::string name = v.name;
    readers_.push_back(std::make_shared<dds::Reader<Status>>(
        p, dds::px4_topic_spec<Status>(topic, "px4_msgs::msg::dds_::VehicleStatus_"),
        [this, name](const Status& s, const dds::SampleMeta&) {
            std::lock_guard lock(mutex_);
            armed_[name] = s.arming_state() == dds::px4::kArmed;
        },
        latest));
}

Px4ArmedWatch::Px4ArmedWatch(dds::Participant& p, const Px4Options& o) {
    topics_.reserve(o.vehicles.size());
    for (const auto& v : o.vehicles) {
        topics_.push_back(dds::px4_topic(v.ns, "out", dds::px4_version(o.version).status_topic));
        if (o.version == dds::Px4Version::v1_14) watch<px4_msgs_v114::msg::dds_::VehicleStatus_>(p, v, topics_.back());
        else if (o.version == dds::Px4Version::v1_16)
            watch<px4_msgs_v116::msg::dds_::VehicleStatus_>(p, v, topics_.back());
        else watch<px4_msgs::msg::dds_::VehicleStatus_>(p, v, topics_.back());
    }
}

std::optional<bool> Px4ArmedWatch::armed(const std::string& vehicle) const {
    std::lock_guard lock(mutex_);
    const auto it = armed_.find(vehicle);
    if (it == armed_.end()) return std::nullopt;
    return it->second;
}

}  // namespace dw::planner
