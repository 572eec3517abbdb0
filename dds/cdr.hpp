#pragma once
// A lab message as the bytes DDS carries: its CDR payload with the encapsulation header (what the
// recorder writes into MCAP and the viewer sends to Foxglove), serialized by the type's own
// Fast DDS support into a buffer kept between calls.
#include <cstdint>
#include <span>

#include <fastdds/rtps/common/SerializedPayload.h>

#include "dds/topics.hpp"

namespace dw::dds {

template <class T>
class CdrWriter {
public:
    // The payload of m (valid until the next call), or empty when the type support refuses it.
    std::span<const std::uint8_t> serialize(const T& m) {
        const std::uint32_t size = support_.getSerializedSizeProvider(const_cast<T*>(&m))();
        if (payload_.max_size < size) payload_.reserve(size);
        payload_.length = 0;
        if (!support_.serialize(const_cast<T*>(&m), &payload_)) return {};
        return {payload_.data, payload_.length};
    }

private:
    typename PubSubOf<T>::type support_;
    eprosima::fastrtps::rtps::SerializedPayload_t payload_{256};
};

}  // namespace dw::dds
