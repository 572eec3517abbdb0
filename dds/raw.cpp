#include "dds/raw.hpp"

#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>
#include <fastdds/dds/topic/TopicDataType.hpp>
#include <cstring>

#include "core/errors.hpp"
#include "dds/participant.hpp"

namespace dw::dds {
namespace fdds = eprosima::fastdds::dds;
namespace rtps = eprosima::fastrtps::rtps;

namespace {
constexpr std::uint32_t kMaxPayload = 65536;  // bytes: a PX4 message, or a lab sample (probe/hostile.hpp)
constexpr int kReaderDepth = 16;

struct RawSample {
    std::vector<std::uint8_t> bytes;
};

// A type that carries the serialized payload as it is, under PX4's type name.
class RawType final : public fdds::TopicDataType {
public:
    RawType(const std::string& name, bool keyed) {
        setName(name.c_str());
        m_typeSize = kMaxPayload;
        m_isGetKeyDefined = keyed;
    }
    bool serialize(void* data, rtps::SerializedPayload_t* payload) override {
        const auto& b = static_cast<RawSample*>(data)->bytes;
        if (b.size() > payload->max_size || b.size() < 4) return false;
        std::memcpy(payload->data, b.data(), b.size());
        payload->length = static_cast<std::uint32_t>(b.size());
        payload->encapsulation = b[1] == 1 ? CDR_LE : CDR_BE;
        return true;
    }
    bool deserialize(rtps::SerializedPayload_t* payload, void* data) override {
        static_cast<RawSample*>(data)->bytes.assign(payload->data, payload->data + payload->length);
        return true;
    }
    std::function<std::uint32_t()> getSerializedSizeProvider(void* data) override {
        return [data] { return static_cast<std::uint32_t>(static_cast<RawSample*>(data)->bytes.size()); };
    }
    void* createData() override { return new RawSample(); }
    void deleteData(void* data) override { delete static_cast<RawSample*>(data); }
    // A keyed topic's samples all under one key (zero): what they are is not read here.
    bool getKey(void*, rtps::InstanceHandle_t* handle, bool) override {
        if (!m_isGetKeyDefined) return false;
        *handle = rtps::InstanceHandle_t();
        handle->value[0] = 1;  // defined, and the same for every sample
        return true;
    }
};
}  // namespace

class RawParticipant::Listener final : public fdds::DataReaderListener {
public:
    explicit Listener(OnBytes f) : f_(std::move(f)) {}
    void on_data_available(fdds::DataReader* r) override {
        RawSample s;
        fdds::SampleInfo info;
        while (r->take_next_sample(&s, &info) == ReturnCode_t::RETCODE_OK)
            if (info.valid_data) f_(s.bytes);
    }
    fdds::DataReader* reader = nullptr;

private:
    OnBytes f_;
};

RawParticipant::RawParticipant(const dds::DdsConfig& lab_cfg, const std::string& name) {
    dds::DdsConfig cfg = lab_cfg;
    cfg.participant_id = dds::kAutoParticipantId;  // a second participant: a fixed id would clash with the lab's
    participant_ = fdds::DomainParticipantFactory::get_instance()->create_participant(
        static_cast<fdds::DomainId_t>(cfg.domain), dds::participant_qos(cfg, name));
    if (participant_ == nullptr) throw RuntimeError("cannot create the simulated PX4's DDS participant");
    publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
    subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
}

RawParticipant::~RawParticipant() {
    for (auto& l : listeners_) l->reader->set_listener(nullptr);
    participant_->delete_contained_entities();
    fdds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
}

fdds::Topic* RawParticipant::topic(const std::string& name, const std::string& type_name, bool keyed) {
    if (auto* t = participant_->find_topic(name, {0, 0})) return t;
    if (participant_->find_type(type_name).empty())
        fdds::TypeSupport(new RawType(type_name, keyed)).register_type(participant_);
    auto* t = participant_->create_topic(name, type_name, fdds::TOPIC_QOS_DEFAULT);
    if (t == nullptr) throw RuntimeError("cannot create topic " + name);
    return t;
}

void RawParticipant::subscribe(const std::string& name, const std::string& type_name, OnBytes on_bytes) {
    std::lock_guard lock(mutex_);
    fdds::DataReaderQos q = fdds::DATAREADER_QOS_DEFAULT;
    q.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
    q.durability().kind = fdds::VOLATILE_DURABILITY_QOS;
    q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
    q.history().depth = kReaderDepth;
    auto l = std::make_unique<Listener>(std::move(on_bytes));
    l->reader = subscriber_->create_datareader(topic(name, type_name), q, l.get());
    if (l->reader == nullptr) throw RuntimeError("cannot create a reader on " + name);
    listeners_.push_back(std::move(l));
}

bool RawParticipant::publish(const std::string& name, const std::string& type_name,
                             const std::vector<std::uint8_t>& payload, const RawWriterSpec& spec) {
    fdds::DataWriter* w = nullptr;
    {
        std::lock_guard lock(mutex_);
        auto& slot = writers_[name];
        if (slot == nullptr) {
            fdds::DataWriterQos q = fdds::DATAWRITER_QOS_DEFAULT;
            q.reliability().kind = fdds::BEST_EFFORT_RELIABILITY_QOS;
            q.durability().kind = fdds::TRANSIENT_LOCAL_DURABILITY_QOS;
            q.history().kind = fdds::KEEP_LAST_HISTORY_QOS;
            q.history().depth = 1;
            if (spec.qos) q = *spec.qos;
            slot = publisher_->create_datawriter(topic(name, type_name, spec.keyed), q);
            if (slot == nullptr) throw RuntimeError("cannot create a writer on " + name);
        }
        w = slot;
    }
    RawSample s{payload};
    return w->write(&s);
}

int RawParticipant::matched_readers(const std::string& name) {
    std::lock_guard lock(mutex_);
    const auto it = writers_.find(name);
    if (it == writers_.end()) return 0;
    fdds::PublicationMatchedStatus st;
    it->second->get_publication_matched_status(st);
    return st.current_count;
}

}  // namespace dw::dds
