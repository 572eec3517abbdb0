#pragma once
// A lab message as the recorder stores it: its CDR bytes (encapsulation header included), for tests
// and benchmarks that write recordings without DDS.
#include <cstdint>
#include <vector>

#include "dds/topics.hpp"

namespace dw::testkit {

template <class T>
std::vector<std::uint8_t> cdr_of(T& message) {
    typename dds::PubSubOf<T>::type support;
    eprosima::fastrtps::rtps::SerializedPayload_t p(support.getSerializedSizeProvider(&message)());
    support.serialize(&message, &p);
    return {p.data, p.data + p.length};
}

}  // namespace dw::testkit
