#pragma once
// Conversions between the lab's nanosecond time and the wire's Time (sec, nanosec).
#include <cmath>

#include "core/clock.hpp"
#include "dw/msg/Common.h"

namespace dw::dds {

using dw::kMaxClockOffsetS;  // core/clock.hpp

// Whether a stamp from a wire can be a time on this clock: within the widest clock error of `now`
// (further off it is a garbled or forged word, and never reaches a vehicle as a capture time).
inline bool stamp_in_time(Nanos stamp, Nanos now) {
    return std::abs(static_cast<double>(stamp - now)) * 1e-9 <= kMaxClockOffsetS;
}

inline msg::Time to_msg(Nanos t) {
    msg::Time m;
    Nanos sec = t / 1'000'000'000;
    Nanos ns = t % 1'000'000'000;
    if (ns < 0) {  // floor division for times before the epoch
        ns += 1'000'000'000;
        --sec;
    }
    m.sec(static_cast<std::int32_t>(sec));
    m.nanosec(static_cast<std::uint32_t>(ns));
    return m;
}

inline Nanos from_msg(const msg::Time& m) {
    return static_cast<Nanos>(m.sec()) * 1'000'000'000 + static_cast<Nanos>(m.nanosec());
}

}  // namespace dw::dds
