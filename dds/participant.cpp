#include "dds/participant.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::dds {
namespace fdds = eprosima::fastdds::dds;

Participant::Participant(const DdsConfig& config, std::string process, Clock& clock)
    : config_(config), process_(std::move(process)), clock_(clock) {
    auto* factory = fdds::DomainParticipantFactory::get_instance();
    participant_ = factory->create_participant(static_cast<fdds::DomainId_t>(config_.domain),
                                               participant_qos(config_, process_));
    if (participant_ == nullptr) {
        throw RuntimeError(log::cat("cannot create a DDS participant on domain ", config_.domain,
                                    " (profile ", to_string(config_.profile), ", transport ",
                                    to_string(config_.transport), ")"));
    }
    publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    if (publisher_ == nullptr || subscriber_ == nullptr) {
        participant_->delete_contained_entities();
        factory->delete_participant(participant_);
        throw RuntimeError("cannot create the DDS publisher/subscriber");
    }
    log::debug("joined domain ", config_.domain, " as ", process_, " (profile ",
               to_string(config_.profile), ", transport ", to_string(config_.transport), ")");
}

Participant::~Participant() {
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

std::string Participant::topic_name(std::string_view suffix) const {
    if (suffix.rfind("rt/", 0) == 0) return std::string(suffix);  // an absolute name (PX4's topics)
    return log::cat("rt/", config_.ns, "/", suffix);
}

fdds::Topic& Participant::find_or_create_topic(const std::string& name,
                                               const std::function<fdds::TypeSupport()>& make_type) {
    std::lock_guard lock(mutex_);
    if (auto* existing = participant_->lookup_topicdescription(name)) {
        return *dynamic_cast<fdds::Topic*>(existing);
    }
    fdds::TypeSupport type = make_type();
    if (participant_->find_type(type.get_type_name()).empty()) {
        if (type.register_type(participant_) != ReturnCode_t::RETCODE_OK) {
            throw RuntimeError("cannot register DDS type " + type.get_type_name());
        }
    }
    fdds::Topic* topic = participant_->create_topic(name, type.get_type_name(), fdds::TOPIC_QOS_DEFAULT);
    if (topic == nullptr) throw RuntimeError("cannot create DDS topic " + name);
    return *topic;
}

std::shared_ptr<EndpointStats> Participant::add_endpoint(const std::string& topic, bool outgoing) {
    auto stats = std::make_shared<EndpointStats>();
    stats->topic = topic;
    stats->outgoing = outgoing;
    std::lock_guard lock(mutex_);
    endpoints_.push_back(stats);
    return stats;
}

std::vector<std::shared_ptr<EndpointStats>> Participant::endpoints() const {
    std::lock_guard lock(mutex_);
    std::vector<std::shared_ptr<EndpointStats>> out;
    for (const auto& weak : endpoints_) {
        if (auto s = weak.lock()) out.push_back(std::move(s));
    }
    return out;
}

void Participant::report_problem(const std::string& line) {
    ++problems_;
    log::error(line);
    std::vector<std::function<void(const std::string&)>> hooks;
    {
        std::lock_guard lock(mutex_);
        hooks = hooks_;
    }
    for (const auto& hook : hooks) hook(line);
}

void Participant::on_problem(std::function<void(const std::string&)> hook) {
    std::lock_guard lock(mutex_);
    hooks_.push_back(std::move(hook));
}

std::string qos_mismatch_line(const std::string& topic, std::string_view type, bool reader_side,
                              const std::string& local_qos, std::uint32_t policy_id,
                              std::uint32_t total_count) {
    return log::cat("QoS mismatch on ", topic, " (", type, "): this ",
                    reader_side ? "reader requests " : "writer offers ", local_qos, " but a ",
                    reader_side ? "writer offers" : "reader requests", " an incompatible ",
                    policy_name(policy_id), "; no samples flow between them (", total_count,
                    total_count == 1 ? " incompatible peer so far)" : " incompatible peers so far)");
}

}  // namespace dw::dds
