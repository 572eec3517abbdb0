#pragma once
// PX4's side of its DDS topics, as bytes: a plain Fast DDS participant whose readers and writers
// carry serialized payloads under PX4's type names (px4_msgs::msg::dds_::<Type>_) with PX4's
// QoS (fmu/in readers BEST_EFFORT VOLATILE KEEP_LAST; fmu/out writers TRANSIENT_LOCAL
// BEST_EFFORT, each created when it first publishes, as PX4's client does). The bytes are read
// and written with px4_sim/wire.hpp, never with the lab's generated types.
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

#include "dds/config.hpp"

namespace dw::px4sim {

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
    bool publish(const std::string& topic, const std::string& type_name, const std::vector<std::uint8_t>& payload);
    // The readers of the lab matched on `topic` now (0 if it was never published).
    int matched_readers(const std::string& topic);

private:
    class Listener;
    eprosima::fastdds::dds::Topic* topic(const std::string& name, const std::string& type_name);

    eprosima::fastdds::dds::DomainParticipant* participant_ = nullptr;
    eprosima::fastdds::dds::Publisher* publisher_ = nullptr;
    eprosima::fastdds::dds::Subscriber* subscriber_ = nullptr;
    std::mutex mutex_;
    std::vector<std::unique_ptr<Listener>> listeners_;
    std::map<std::string, eprosima::fastdds::dds::DataWriter*> writers_;
};

}  // namespace dw::px4sim
