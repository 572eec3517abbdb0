#pragma once
// DDS topics as bytes: a plain Fast DDS participant whose readers and writers carry serialized
// payloads, as they are, under any type name. By default with PX4's QoS (fmu/in readers
// BEST_EFFORT VOLATILE KEEP_LAST; fmu/out writers TRANSIENT_LOCAL BEST_EFFORT, each created when it
// first publishes, as PX4's client does): PX4's side of its topics, whose bytes px4_sim/wire.hpp
// reads and writes. With a lab topic's QoS: malformed samples on the lab's own topics
// (probe/hostile.hpp), which no generated type would write.
#include <fastdds/dds/domain/DomainParticipant.hpp>
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include <fastdds/dds/publisher/qos/DataWriterQos.hpp>
#include <optional>

#include "dds/config.hpp"

namespace dw::dds {

// How a raw topic's writer is made (on its first publish): PX4's QoS unless given; a keyed type for
// a keyed topic (a keyless writer matches no keyed reader), every sample under one key.
struct RawWriterSpec {
    std::optional<eprosima::fastdds::dds::DataWriterQos> qos;
    bool keyed = false;
};

class RawParticipant {
public:
    using OnBytes = std::function<void(std::span<const std::uint8_t>)>;
    RawParticipant(const dds::DdsConfig& cfg, const std::string& name);
    ~RawParticipant();
    RawParticipant(const RawParticipant&) = delete;
    RawParticipant& operator=(const RawParticipant&) = delete;

    // Every sample on `topic` (a full name: rt/...), its payload with the encapsulation, on a Fast DDS thread.
    void subscribe(const std::string& topic, const std::string& type_name, OnBytes on_bytes);
    // Publishes the payload (encapsulation included) on `topic`.
    bool publish(const std::string& topic, const std::string& type_name, const std::vector<std::uint8_t>& payload,
                 const RawWriterSpec& spec = {});
    // The readers of the lab matched on `topic` now (0 if it was never published).
    int matched_readers(const std::string& topic);

private:
    class Listener;
    eprosima::fastdds::dds::Topic* topic(const std::string& name, const std::string& type_name, bool keyed = false);

    eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
    eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
    eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
    std::mutex mutex_;
    std::vector<std::unique_ptr<Listener>> listeners_;
    std::map<std::string, eprosima::fastdds::dds::DataWriter*> writers_;
};

}  // namespace dw::dds
