#pragma once
// The lab's clock service (issue 19), NTP-style: every process (through its heartbeat) asks the
// reference clock — the recorder, whose clock stamps every recorded message — four timestamps at a
// time, and keeps the offset of the exchange with the smallest round trip among the last few. The
// offset rides on the process's heartbeat (ProcessStatus.clock_offset_s), so it is recorded, shown
// in `dw-lab run`'s status lines and used by `dw-recorder export` to put stamps on one clock.
#include <deque>
#include <mutex>
#include <optional>

#include "dds/endpoint.hpp"

namespace dw::dds {

struct ClockEstimate {
    double offset_s = 0;       // this process's clock minus the reference's
    double uncertainty_s = 0;  // half the exchange's round trip: the offset is within ± this
};

// One process's exchanges with the reference; the estimate is the one with the smallest round
// trip among the last kWindow (queueing only ever adds delay, and adds it unevenly).
class ClockFilter {
public:
    static constexpr std::size_t kWindow = 8;
    // t1 and t4: this process's clock at request and answer; t2 and t3: the reference's at
    // receipt and reply. An exchange that went backwards (t4 < t1 or t3 < t2) is ignored.
    void add(Nanos t1, Nanos t2, Nanos t3, Nanos t4);
    std::optional<ClockEstimate> estimate() const;

private:
    std::deque<ClockEstimate> exchanges_;
};

// The reference: answers each request with its clock at receipt and at reply.
class ClockReference {
public:
    explicit ClockReference(Participant& p);

private:
    Participant& p_;
    Writer<msg::ClockProbe> answers_;
    std::mutex mutex_;  // answers_ is written from the request reader's thread only, but guard it
    Reader<msg::ClockProbe> requests_;
};

// A process's side: ask() sends a request (the heartbeat does, every period); answers for this
// process feed the filter.
class ClockClient {
public:
    explicit ClockClient(Participant& p);
    void ask();
    std::optional<ClockEstimate> estimate() const;

private:
    Participant& p_;
    Writer<msg::ClockProbe> requests_;
    mutable std::mutex mutex_;
    ClockFilter filter_;
    std::map<std::uint64_t, Nanos> asked_;  // probe -> t1, for answers still to come
    std::uint64_t next_probe_ = 0;
    Reader<msg::ClockProbe> answers_;
};

}  // namespace dw::dds
