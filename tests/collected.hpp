#pragma once
// Every sample a lab topic carries, in arrival order, for a test to look at.
#include <mutex>
#include <vector>

#include "dds/endpoint.hpp"

namespace dw::test {

template <class T>
class Collected {
public:
    Collected(dds::Participant& p, const dds::Topic<T>& topic)
        : reader_(p, topic, [this](const T& s, const dds::SampleMeta&) {
              std::lock_guard lock(mutex_);
              samples_.push_back(s);
          }) {}
    std::vector<T> samples() const {  // a copy of those so far
        std::lock_guard lock(mutex_);
        return samples_;
    }
    void clear() {
        std::lock_guard lock(mutex_);
        samples_.clear();
    }
    dds::Reader<T>& reader() { return reader_; }

private:
    mutable std::mutex mutex_;
    std::vector<T> samples_;
    dds::Reader<T> reader_;  // last: its callback uses the members above
};

}  // namespace dw::test
