#include "dds/qos.hpp"

#include "core/log.hpp"

namespace dw::dds {
namespace fdds = eprosima::fastdds::dds;

namespace {
struct Shape {
    bool reliable;
    bool transient_local;
    int depth;
    bool liveliness;
};

Shape shape_of(QosProfile p, const QosOverrides& o) {
    Shape s{};
    switch (p) {
        case QosProfile::sensor: s = {false, false, 16, false}; break;
        case QosProfile::state: s = {true, true, 1, false}; break;
        case QosProfile::command: s = {true, false, 64, false}; break;
        case QosProfile::heartbeat: s = {true, false, 1, true}; break;
        case QosProfile::px4: s = {false, false, 16, false}; break;
    }
    if (o.reliable) s.reliable = *o.reliable;
    if (o.transient_local) s.transient_local = *o.transient_local;
    if (o.depth) s.depth = *o.depth;
    return s;
}

// Heartbeat writers assert liveliness automatically; a reader notices a silent peer after the lease.
const eprosima::fastrtps::Duration_t kLease(2, 0);
const eprosima::fastrtps::Duration_t kAnnounce(0, 500'000'000);

// At most kMaxInstances instances of `depth` samples each.
template <class Q>
void limit_instances(Q& q, int depth) {
    q.resource_limits().max_instances = kMaxInstances;
    q.resource_limits().max_samples_per_instance = depth;
    q.resource_limits().max_samples = kMaxInstances * depth;
}

template <class Q>
std::string describe_common(const Q& q) {
    return log::cat(q.reliability().kind == fdds::RELIABLE_RELIABILITY_QOS ? "RELIABLE" : "BEST_EFFORT", " ",
                    q.durability().kind == fdds::TRANSIENT_LOCAL_DURABILITY_QOS ? "TRANSIENT_LOCAL" : "VOLATILE", " ",
                    q.history().kind == fdds::KEEP_LAST_HISTORY_QOS ? "KEEP_LAST(" : "KEEP_ALL(", q.history().depth,
                    ")");
}
}  // namespace

std::string to_string(QosProfile p) {
    switch (p) {
        case QosProfile::sensor: return "sensor";
        case QosProfile::state: return "state";
        case QosProfile::command: return "command";
        case QosProfile::heartbeat: return "heartbeat";
        case QosProfile::px4: return "px4";
    }
    return "?";
}

namespace {
// What a writer's and a reader's QoS share: reliability, durability, history, limits, liveliness.
template <class Q>
void apply_shape(Q& q, const Shape& s) {
    q.reliability().kind = s.reliable ? fdds::RELIABLE_RELIABILITY_QOS : fdds::BEST_EFFORT_RELIABILITY_QOS;
    q.durability().kind = s.transient_local ? fdds::TRANSIENT_LOCAL_DURABILITY_QOS : fdds::VOLATILE_DURABILITY_QOS;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = s.depth;
    limit_instances(q, s.depth);
    if (s.liveliness) {
        q.liveliness().kind = fdds::AUTOMATIC_LIVELINESS_QOS;
        q.liveliness().lease_duration = kLease;
    }
}
}  // namespace

fdds::DataWriterQos writer_qos(QosProfile p, const QosOverrides& o) {
    const Shape s = shape_of(p, o);
    fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
    apply_shape(q, s);
    // Synchronous publishing: the sample is handed to the transport in write() (lowest latency).
    q.publish_mode().kind = fdds::SYNCHRONOUS_PUBLISH_MODE;
    if (s.liveliness) q.liveliness().announcement_period = kAnnounce;
    return q;
}

fdds::DataReaderQos reader_qos(QosProfile p, const QosOverrides& o) {
    const Shape s = shape_of(p, o);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    apply_shape(q, s);
    // Another system's messages may be longer than the part the lab reads (PX4's VehicleStatus:
    // the lab's type is its prefix); a preallocated payload pool would drop them.
    if (p == QosProfile::px4)
        q.endpoint().history_memory_policy = eprosima::fastrtps::rtps::DYNAMIC_REUSABLE_MEMORY_MODE;
    return q;
}

std::string describe(const fdds::DataWriterQos& q) { return describe_common(q); }
std::string describe(const fdds::DataReaderQos& q) { return describe_common(q); }

std::string policy_name(std::uint32_t id) {
    switch (id) {
        case fdds::DURABILITY_QOS_POLICY_ID: return "DURABILITY";
        case fdds::PRESENTATION_QOS_POLICY_ID: return "PRESENTATION";
        case fdds::DEADLINE_QOS_POLICY_ID: return "DEADLINE";
        case fdds::LATENCYBUDGET_QOS_POLICY_ID: return "LATENCY_BUDGET";
        case fdds::OWNERSHIP_QOS_POLICY_ID: return "OWNERSHIP";
        case fdds::LIVELINESS_QOS_POLICY_ID: return "LIVELINESS";
        case fdds::PARTITION_QOS_POLICY_ID: return "PARTITION";
        case fdds::RELIABILITY_QOS_POLICY_ID: return "RELIABILITY";
        case fdds::DESTINATIONORDER_QOS_POLICY_ID: return "DESTINATION_ORDER";
        case fdds::HISTORY_QOS_POLICY_ID: return "HISTORY";
        case fdds::DATAREPRESENTATION_QOS_POLICY_ID: return "DATA_REPRESENTATION";
        case fdds::TYPECONSISTENCYENFORCEMENT_QOS_POLICY_ID: return "TYPE_CONSISTENCY";
        case fdds::DISABLEPOSITIVEACKS_QOS_POLICY_ID: return "DISABLE_POSITIVE_ACKS";
        default: return log::cat("policy #", id);
    }
}

}  // namespace dw::dds
