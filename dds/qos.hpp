#pragma once
// The lab's named QoS profiles. Every topic has exactly one (see topics.hpp); both ends of a
// topic take it from there, so they match unless someone overrides it on purpose.
#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <fastdds/dds/subscriber/qos/DataReaderQos.hpp>
#include <optional>
#include <string>

namespace dw::dds {

enum class QosProfile {
    sensor,     // streams (wrench, mocap, setpoints): BEST_EFFORT, VOLATILE, KEEP_LAST
    state,      // latched state and plans: RELIABLE, TRANSIENT_LOCAL, KEEP_LAST 1 per instance
    command,    // commands: RELIABLE, VOLATILE, KEEP_LAST (deep)
    heartbeat,  // process status: RELIABLE, VOLATILE, KEEP_LAST 1, automatic liveliness
    px4,        // PX4's uXRCE-DDS topics: BEST_EFFORT, VOLATILE, KEEP_LAST, as PX4's own readers
                // (its writers are TRANSIENT_LOCAL BEST_EFFORT: they match); never awaits the lab's readers
};

// Instances a keyed topic holds (its reader and its writer): the widest keyed set of a lab, its
// processes (the heartbeat, kMaxPeers) or vehicles. Fast DDS's default is 10: an eleventh process's
// heartbeat, or a vehicle after a writer's ten invented ids, was refused. Each instance keeps its
// profile's depth, so a topic holds at most kMaxInstances × depth samples.
inline constexpr int kMaxInstances = 256;

// Deliberate deviations from a profile (tools and tests).
struct QosOverrides {
    std::optional<bool> reliable;
    std::optional<bool> transient_local;
    std::optional<int> depth;
};

std::string to_string(QosProfile p);
eprosima::fastdds::dds::DataWriterQos writer_qos(QosProfile p, const QosOverrides& o = {});
eprosima::fastdds::dds::DataReaderQos reader_qos(QosProfile p, const QosOverrides& o = {});
// "RELIABLE TRANSIENT_LOCAL KEEP_LAST(1)"
std::string describe(const eprosima::fastdds::dds::DataWriterQos& q);
std::string describe(const eprosima::fastdds::dds::DataReaderQos& q);
// "RELIABILITY", "DURABILITY", ...
std::string policy_name(std::uint32_t policy_id);

}  // namespace dw::dds
