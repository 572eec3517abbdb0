#pragma once
// Conversions between the lab's nanosecond time and the wire's Time (sec, nanosec).
#include <cmath>

#include "core/clock.hpp"
#include "dw/msg/Common.h"

namespace dw::dds {

using dw::kMaxClockOffsetS;  // core/clock.hpp

// Whether a stamp from a wire can be a time on this clock: within the widest clock error of `now`
// (further off it is a garbled or forged word, and never reaches a vehicle as a capture time).
inline bool stamp_in_time(Nanos stamp, Nanos now) { return std::abs(to_seconds(stamp - now)) <= kMaxClockOffsetS; }

inline msg::Time to_msg(Nanos t) {
    msg::Time m;
    Nanos sec = t / kNanosPerSecond;
    Nanos ns = t % kNanosPerSecond;
    if (ns < 0) {  // floor division for times before the epoch
        ns += kNanosPerSecond;
        --sec;
    }
    m.sec(static_cast<std::int32_t>(sec));
    m.nanosec(static_cast<std::uint32_t>(ns));
    return m;
}

inline Nanos from_msg(const msg::Time& m) {
    return static_cast<Nanos>(m.sec()) * kNanosPerSecond + static_cast<Nanos>(m.nanosec());
}

}  // namespace dw::dds
