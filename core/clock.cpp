#include "core/clock.hpp"

#include <algorithm>
#include <cmath>

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

namespace {
bool within_step(Nanos a, Nanos b) { return std::abs(to_seconds(a - b)) <= kMaxStampStepS; }
}  // namespace

bool StampGate::accept(Nanos stamp) {
    if (!started_ || within_step(stamp, newest_)) {
        newest_ = started_ ? std::max(newest_, stamp) : stamp;
        started_ = true;
        stray_run_ = 0;
        return true;
    }
    stray_run_ = stray_run_ > 0 && within_step(stamp, stray_) ? stray_run_ + 1 : 1;
    stray_ = stamp;
    if (stray_run_ < kStampsToFollow) {
        ++strays_;
        return false;
    }
    newest_ = stamp;  // the stream's clock moved: follow it
    stray_run_ = 0;
    return true;
}

}  // namespace dw
