#pragma once
// The one place every sample the lab receives is decoded. A generated type's deserialize throws on
// a malformed sample — an unknown CDR encapsulation id (fastcdr's BadParamException, which the
// generated code does not catch) — on Fast DDS's listener thread, where nothing above can catch
// it: the reading process aborted (issue 70). Here it is caught: the sample is refused (Fast DDS
// drops a sample its type cannot deserialize and goes on with the next), counted for the type,
// and said once. So is a sample that decodes but whose header stamp is no time (nanosec at or
// beyond a second: every reader's arithmetic on stamps assumes it below).
#include <fastdds/rtps/common/SerializedPayload.h>

#include <atomic>
#include <cstdint>
#include <exception>
#include <functional>
#include <memory>
#include <string>

#include "core/clock.hpp"

namespace dw::dds {

// What a guarded type tells its participant: the type's name and what the decoder said, the first
// time a sample of that type is refused; the running count is in `refused`.
struct Refusals {
    std::atomic<std::uint64_t> refused{0};
    std::function<void(const std::string& type, const std::string& what)> first;
};

template <class PubSub>
class Guarded final : public PubSub {
public:
    explicit Guarded(std::shared_ptr<Refusals> refusals) : refusals_(std::move(refusals)) {}
    bool deserialize(eprosima::fastrtps::rtps::SerializedPayload_t* payload, void* data) override {
        try {
            if (!PubSub::deserialize(payload, data)) return false;
            using T = typename PubSub::type;
            if constexpr (requires(T & m) { m.header().stamp().nanosec(); }) {
                if (static_cast<T*>(data)->header().stamp().nanosec() >= static_cast<std::uint32_t>(kNanosPerSecond))
                    return refuse("its header stamp's nanosec is a second or more");
            }
            return true;
        } catch (const std::exception& e) {
            return refuse(e.what());
        }
    }

private:
    bool refuse(const std::string& what) {
        if (refusals_->refused.fetch_add(1) == 0 && refusals_->first) refusals_->first(this->getName(), what);
        return false;
    }

    std::shared_ptr<Refusals> refusals_;
};

}  // namespace dw::dds
