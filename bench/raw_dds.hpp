#pragma once
// Raw Fast DDS as a process would use it without the lab's layer, for the benchmarks' anchors:
// one participant with the same participant QoS as the layer's, the WrenchStamped type, topics,
// a publisher and a subscriber.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <fastdds/dds/publisher/Publisher.hpp>
#include <fastdds/dds/subscriber/Subscriber.hpp>

#include "dds/config.hpp"
#include "dw/msg/WrenchPubSubTypes.h"

namespace dw::bench {

class RawParticipant {
public:
    RawParticipant(const dds::DdsConfig& cfg, const std::string& name) {
        namespace fdds = eprosima::fastdds::dds;
        participant_ = fdds::DomainParticipantFactory::get_instance()->create_participant(
            static_cast<fdds::DomainId_t>(cfg.domain), dds::participant_qos(cfg, name));
        type_ = fdds::TypeSupport(new msg::WrenchStampedPubSubType());
        type_.register_type(participant_);
        publisher_ = participant_->create_publisher(fdds::PUBLISHER_QOS_DEFAULT);
        subscriber_ = participant_->create_subscriber(fdds::SUBSCRIBER_QOS_DEFAULT);
    }
    ~RawParticipant() {
        participant_->delete_contained_entities();
        eprosima::fastdds::dds::DomainParticipantFactory::get_instance()->delete_participant(participant_);
    }
    RawParticipant(const RawParticipant&) = delete;
    RawParticipant& operator=(const RawParticipant&) = delete;

    eprosima::fastdds::dds::Topic* topic(const std::string& name) {
        return participant_->create_topic(name, type_.get_type_name(), eprosima::fastdds::dds::TOPIC_QOS_DEFAULT);
    }
    eprosima::fastdds::dds::Publisher* publisher() { return publisher_; }
    eprosima::fastdds::dds::Subscriber* subscriber() { return subscriber_; }

private:
    eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
    eprosima::fastdds::dds::TypeSupport type_;
    eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
    eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
};

}  // namespace dw::bench
