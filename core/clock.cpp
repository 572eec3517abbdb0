#include "core/clock.hpp"

namespace dw {

Nanos SystemClock::now_ns() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch())
        .count();
}

Nanos SystemClock::monotonic_ns() const {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

SystemClock& SystemClock::instance() {
    static SystemClock clock;
    return clock;
}

Nanos ManualClock::now_ns() const {
    std::lock_guard lock(mutex_);
    return now_;
}

Nanos ManualClock::monotonic_ns() const { return now_ns(); }

void ManualClock::advance(std::chrono::nanoseconds d) {
    std::lock_guard lock(mutex_);
    now_ += d.count();
}

void ManualClock::set(Nanos t) {
    std::lock_guard lock(mutex_);
    now_ = t;
}

}  // namespace dw
