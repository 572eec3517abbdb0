#include "dds/participant.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/domain/DomainParticipantListener.hpp>
#include <fastdds/rtps/builtin/data/ParticipantProxyData.h>
#include <fastdds/rtps/common/InstanceHandle.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"

namespace dw::dds {
namespace fdds = eprosima::fastdds::dds;
namespace frtps = eprosima::fastrtps::rtps;

namespace {
// The identity a participant authenticated with: its certificate's common name, from the identity
// token it announced (PKI-DH's "dds.cert.sn", the subject, e.g. "CN=planner"); "" without one.
std::string common_name_of(const frtps::ParticipantProxyData& p) {
    for (const auto& property : p.identity_token_.properties()) {
        if (property.name() != "dds.cert.sn") continue;
        const std::string& subject = property.value();
        const auto at = subject.find("CN=");
        if (at == std::string::npos) return subject;
        const auto end = subject.find_first_of(",/", at);
        return subject.substr(at + 3, end == std::string::npos ? std::string::npos : end - at - 3);
    }
    return {};
}
}  // namespace

class Participant::Discovery final : public fdds::DomainParticipantListener {
public:
    void on_participant_discovery(fdds::DomainParticipant*, frtps::ParticipantDiscoveryInfo&& info) override {
        std::lock_guard lock(mutex_);
        const bool gone = info.status == frtps::ParticipantDiscoveryInfo::REMOVED_PARTICIPANT ||
                          info.status == frtps::ParticipantDiscoveryInfo::DROPPED_PARTICIPANT;
        if (gone) {
            peers_.erase(info.info.m_guid.guidPrefix);
        } else {
            peers_[info.info.m_guid.guidPrefix] = {info.info.m_participantName.to_string(), common_name_of(info.info)};
        }
    }
    std::string name_of(const frtps::GuidPrefix_t& prefix) const { return find(prefix).name; }
    std::string identity_of(const frtps::GuidPrefix_t& prefix) const { return find(prefix).identity; }

private:
    struct Peer {
        std::string name, identity;
    };
    Peer find(const frtps::GuidPrefix_t& prefix) const {
        std::lock_guard lock(mutex_);
        const auto it = peers_.find(prefix);
        return it == peers_.end() ? Peer{} : it->second;
    }
    mutable std::mutex mutex_;
    std::map<frtps::GuidPrefix_t, Peer> peers_;
};

Participant::Participant(const DdsConfig& config, std::string process, Clock& clock)
    : config_(config), process_(std::move(process)), clock_(clock), discovery_(std::make_unique<Discovery>()) {
    auto* factory = fdds::DomainParticipantFactory::get_instance();
    participant_ =
        factory->create_participant(static_cast<fdds::DomainId_t>(config_.domain), participant_qos(config_, process_),
                                    discovery_.get(), fdds::StatusMask::none());
    if (participant_ == nullptr) {
        throw RuntimeError(log::cat("cannot create a DDS participant on domain ", config_.domain, " (profile ",
                                    to_string(config_.profile), ", transport ", to_string(config_.transport), ")"));
    }
    publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    if (publisher_ == nullptr || subscriber_ == nullptr) {
        participant_->delete_contained_entities();
        factory->delete_participant(participant_);
        throw RuntimeError("cannot create the DDS publisher/subscriber");
    }
    log::debug("joined domain ", config_.domain, " as ", process_, " (profile ", to_string(config_.profile),
               ", transport ", to_string(config_.transport), ")");
}

Participant::~Participant() {
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

std::string Participant::identity_of(const fdds::InstanceHandle_t& endpoint) const {
    return discovery_->identity_of(frtps::iHandle2GUID(endpoint).guidPrefix);
}

std::vector<std::string> Participant::unmatched_readers(const std::vector<fdds::InstanceHandle_t>& matched,
                                                        const std::vector<std::string>& processes) const {
    std::vector<std::string> missing = processes;
    for (const auto& h : matched) {
        const std::string name = discovery_->name_of(frtps::iHandle2GUID(h).guidPrefix);
        missing.erase(std::remove(missing.begin(), missing.end(), name), missing.end());
    }
    return missing;
}

namespace {
constexpr auto kAwaitPoll = std::chrono::milliseconds(5);
// The writer sees a reader match before the reader has matched the writer; a best-effort sample
// sent in between is dropped by the reader. This covers the reader's side on one network.
constexpr auto kReaderSideMargin = std::chrono::milliseconds(100);
}  // namespace

bool await_required_readers(Participant& p, const std::function<std::vector<fdds::InstanceHandle_t>()>& matched,
                            const std::string& topic) {
    const auto& wanted = p.config().await_readers;
    if (wanted.empty()) return true;
    const auto start = std::chrono::steady_clock::now();
    const auto deadline = start + to_millis(p.config().await_timeout_s);
    std::vector<std::string> missing = p.unmatched_readers(matched(), wanted);
    while (!missing.empty() && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(kAwaitPoll);
        missing = p.unmatched_readers(matched(), wanted);
    }
    if (!missing.empty()) {
        log::warn(topic, ": no reader from ", log::join(missing), " after ", p.config().await_timeout_s,
                  " s; publishing anyway (what it misses until it joins is lost)");
        return false;
    }
    std::this_thread::sleep_for(kReaderSideMargin);
    log::debug(topic, ": awaited readers matched after ",
               std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), " s");
    return true;
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

std::shared_ptr<Refusals> Participant::refusals() {
    auto r = std::make_shared<Refusals>();
    r->first = [this](const std::string& type, const std::string& what) {
        report_problem(log::cat("a malformed ", type, " sample refused (", what,
                                "); this process goes on, and further ones are counted"));
    };
    std::lock_guard lock(refusals_mutex_);
    refusals_.push_back(r);
    return r;
}

std::uint64_t Participant::refused_samples() const {
    std::lock_guard lock(refusals_mutex_);
    std::uint64_t n = 0;
    for (const auto& r : refusals_) n += r->refused.load();
    return n;
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
                              const std::string& local_qos, std::uint32_t policy_id, std::uint32_t total_count) {
    return log::cat("QoS mismatch on ", topic, " (", type, "): this ",
                    reader_side ? "reader requests " : "writer offers ", local_qos, " but a ",
                    reader_side ? "writer offers" : "reader requests", " an incompatible ", policy_name(policy_id),
                    "; no samples flow between them (", total_count,
                    total_count == 1 ? " incompatible peer so far)" : " incompatible peers so far)");
}

}  // namespace dw::dds
