#pragma once
// Time is injected: logic that tests must drive takes a Clock&, never reads a global clock.
#include <chrono>
#include <cstdint>
#include <mutex>

#include "core/numbers.hpp"

namespace dw {

// Nanoseconds since the Unix epoch (wall time, what goes into message stamps).
using Nanos = std::int64_t;

// The widest clock error between two lab processes: what --clock-offset may simulate, and beyond
// which a measured offset or delay (on the wire, in a flight's meta.json) is no measurement.
inline constexpr double kMaxClockOffsetS = 3600;
// A measured (or simulated) clock offset, and a process's own pipeline delay: what can be a time.
inline constexpr Range kClockOffsetRange{-kMaxClockOffsetS, kMaxClockOffsetS, "s"};
inline constexpr Range kPipelineDelayRange{0, kMaxClockOffsetS, "s"};

// The stamps of one stream from a wire (mocap frames), held to themselves (issue 70), whatever
// clock the reader runs on: each stamp within kMaxStampStepS of the newest accepted, forward or
// back (a frame the network reordered passes, though it is not the newest). A stamp further off is
// a stray, refused and counted, unless kStampsToFollow strays in a row agree (each within the step
// of the one before): then the stream's own clock moved (Motive restarted, a replay began) and it is
// followed from there. A lone garbled or forged stamp never moves it.
inline constexpr double kMaxStampStepS = 1.0;
inline constexpr int kStampsToFollow = 5;

class StampGate {
public:
    bool accept(Nanos stamp);
    std::uint64_t strays() const { return strays_; }

private:
    bool started_ = false;
    Nanos newest_ = 0;
    Nanos stray_ = 0;  // the last stray, while a run of them lasts
    int stray_run_ = 0;
    std::uint64_t strays_ = 0;
};

class Clock {
public:
    virtual ~Clock() = default;
    // Wall-clock time stamped into messages.
    virtual Nanos now_ns() const = 0;
    // Monotonic time for timeouts and rates (never jumps).
    virtual Nanos monotonic_ns() const = 0;
};

class SystemClock final : public Clock {
public:
    Nanos now_ns() const override;
    Nanos monotonic_ns() const override;
    static SystemClock& instance();
};

// A clock that moves only when told to; both time bases advance together.
class ManualClock final : public Clock {
public:
    explicit ManualClock(Nanos start_ns = 1'700'000'000'000'000'000) : now_(start_ns) {}
    Nanos now_ns() const override;
    Nanos monotonic_ns() const override;
    void advance(std::chrono::nanoseconds d);
    void set(Nanos t);

private:
    mutable std::mutex mutex_;
    Nanos now_;
};

// Another clock's wall time shifted by a fixed offset (a simulated process's clock error:
// --clock-offset); its monotonic time is the other clock's.
class OffsetClock final : public Clock {
public:
    OffsetClock(const Clock& base, Nanos offset_ns) : base_(&base), offset_ns_(offset_ns) {}
    Nanos now_ns() const override { return base_->now_ns() + offset_ns_; }
    Nanos monotonic_ns() const override { return base_->monotonic_ns(); }

private:
    const Clock* base_;
    Nanos offset_ns_;
};

inline constexpr Nanos kNanosPerSecond = 1'000'000'000;
inline double to_seconds(Nanos ns) { return static_cast<double>(ns) * 1e-9; }
inline Nanos from_seconds(double s) { return static_cast<Nanos>(s * 1e9); }

}  // namespace dw
