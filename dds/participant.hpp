#pragma once
// A lab process's membership of the DDS domain: one participant, one publisher, one subscriber,
// topics created once, per-endpoint statistics for the heartbeat, and problem reporting (QoS
// mismatches) as one clear line each.
#include <fastdds/dds/common/InstanceHandle.hpp>
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/Topic.hpp>
#include <fastdds/dds/topic/TypeSupport.hpp>
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/clock.hpp"
#include "dds/config.hpp"
#include "dds/guarded.hpp"
#include "dds/topics.hpp"

namespace dw::dds {

// Counters of one writer or reader, read by the heartbeat.
struct EndpointStats {
    std::string topic;
    bool outgoing = false;
    std::atomic<std::uint64_t> samples{0};
    std::atomic<std::uint64_t> lost{0};
};

class Participant {
public:
    // Throws dw::RuntimeError when Fast DDS refuses the participant.
    Participant(const DdsConfig& config, std::string process, Clock& clock = SystemClock::instance());
    ~Participant();
    Participant(const Participant&) = delete;
    Participant& operator=(const Participant&) = delete;

    eprosima::fastdds::dds::DomainParticipant& native() { return *participant_; }
    eprosima::fastdds::dds::Publisher& publisher() { return *publisher_; }
    eprosima::fastdds::dds::Subscriber& subscriber() { return *subscriber_; }
    const DdsConfig& config() const { return config_; }
    const std::string& process() const { return process_; }
    Clock& clock() const { return clock_; }

    // rt/<namespace>/<suffix>; a suffix that starts with rt/ is already a full name.
    std::string topic_name(std::string_view suffix) const;

    template <class T>
    eprosima::fastdds::dds::Topic& topic(const Topic<T>& spec) {
        // Every type decoded through dds/guarded.hpp: a malformed sample is refused, not fatal.
        return find_or_create_topic(topic_name(spec.suffix), [this] {
            return eprosima::fastdds::dds::TypeSupport(new Guarded<typename PubSubOf<T>::type>(refusals()));
        });
    }

    std::shared_ptr<EndpointStats> add_endpoint(const std::string& topic, bool outgoing);
    // Endpoints still alive, in creation order.
    std::vector<std::shared_ptr<EndpointStats>> endpoints() const;

    // Logs the line as an error and counts it; hooks (tests, heartbeat) see it too.
    void report_problem(const std::string& line);
    void on_problem(std::function<void(const std::string&)> hook);
    std::uint64_t problem_count() const { return problems_; }
    // Samples refused because they do not decode (dds/guarded.hpp), over every type.
    std::uint64_t refused_samples() const;

    // The names in `processes` (participant names: recorder, predictor, ...) that own none of the
    // `matched` readers (a writer's matched subscriptions).
    std::vector<std::string> unmatched_readers(const std::vector<eprosima::fastdds::dds::InstanceHandle_t>& matched,
                                               const std::vector<std::string>& processes) const;

    // Under DDS Security, the identity (certificate common name) the participant owning this
    // remote endpoint authenticated with; "" without DDS Security or before it is discovered.
    std::string identity_of(const eprosima::fastdds::dds::InstanceHandle_t& endpoint) const;

private:
    std::shared_ptr<Refusals> refusals();  // one per type made: the first refusal said as a problem
    class Discovery;                       // remembers each discovered participant's name and identity
    eprosima::fastdds::dds::Topic& find_or_create_topic(
        const std::string& name, const std::function<eprosima::fastdds::dds::TypeSupport()>& make_type);

    DdsConfig config_;
    std::string process_;
    Clock& clock_;
    eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
    eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
    eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
    mutable std::mutex mutex_;
    std::vector<std::weak_ptr<EndpointStats>> endpoints_;
    std::vector<std::function<void(const std::string&)>> hooks_;
    std::atomic<std::uint64_t> problems_{0};
    mutable std::mutex refusals_mutex_;  // not mutex_: types are made while it is held
    std::vector<std::shared_ptr<Refusals>> refusals_;
    std::unique_ptr<Discovery> discovery_;
};

// Holds a sensor writer's first sample until the readers of the processes in the participant's
// `await_readers` matched it, or `await_timeout_s` passed (then one warning line; it publishes
// anyway). Returns at once when there is nothing to await. True: they matched (or none awaited).
// `matched`: the writer's matched subscriptions now (Fast DDS 2.9.1 leaves
// DataWriter::get_matched_subscriptions unsupported, so the writer keeps them from its listener).
bool await_required_readers(Participant& p,
                            const std::function<std::vector<eprosima::fastdds::dds::InstanceHandle_t>()>& matched,
                            const std::string& topic);

// "QoS mismatch on rt/lab/stand/wrench (dw::msg::WrenchStamped): this reader requests
// RELIABLE VOLATILE KEEP_LAST(16) but a writer offers an incompatible RELIABILITY; no samples
// will flow between them"
std::string qos_mismatch_line(const std::string& topic, std::string_view type, bool reader_side,
                              const std::string& local_qos, std::uint32_t policy_id, std::uint32_t total_count);

}  // namespace dw::dds
