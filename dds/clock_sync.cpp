#include "dds/clock_sync.hpp"

#include <algorithm>

#include "dds/time.hpp"

namespace dw::dds {

namespace {
constexpr std::size_t kMaxOutstanding = 32;  // requests never answered are forgotten beyond this
}  // namespace

void ClockFilter::add(Nanos t1, Nanos t2, Nanos t3, Nanos t4) {
    if (t4 < t1 || t3 < t2) return;
    const double round_trip = to_seconds((t4 - t1) - (t3 - t2));
    // NTP's theta is reference minus process; the lab states process minus reference.
    const double theta = 0.5 * (to_seconds(t2 - t1) + to_seconds(t3 - t4));
    exchanges_.push_back({-theta, 0.5 * std::max(round_trip, 0.0)});
    if (exchanges_.size() > kWindow) exchanges_.pop_front();
}

std::optional<ClockEstimate> ClockFilter::estimate() const {
    if (exchanges_.empty()) return std::nullopt;
    return *std::min_element(exchanges_.begin(), exchanges_.end(), [](const ClockEstimate& a, const ClockEstimate& b) {
        return a.uncertainty_s < b.uncertainty_s;
    });
}

ClockReference::ClockReference(Participant& p)
    : p_(p),
      answers_(p, topics::clock_reply),
      requests_(p, topics::clock_request, [this](const msg::ClockProbe& q, const SampleMeta&) {
          const Nanos received = p_.clock().now_ns();
          msg::ClockProbe a;  // the asker's process and probe; a header of the reference's own
          a.process(q.process());
          a.probe(q.probe());
          a.reference_receive(to_msg(received));
          std::lock_guard lock(mutex_);
          const Nanos sent = p_.clock().now_ns();
          a.reference_send(to_msg(sent));
          a.header().stamp(to_msg(sent));
          answers_.write(a);
      }) {}

ClockClient::ClockClient(Participant& p)
    : p_(p),
      requests_(p, topics::clock_request),
      answers_(p, topics::clock_reply, [this](const msg::ClockProbe& a, const SampleMeta&) {
          const Nanos t4 = p_.clock().now_ns();
          if (a.process() != p_.process()) return;
          std::lock_guard lock(mutex_);
          const auto it = asked_.find(a.probe());
          if (it == asked_.end()) return;
          filter_.add(it->second, from_msg(a.reference_receive()), from_msg(a.reference_send()), t4);
          asked_.erase(it);
      }) {}

void ClockClient::ask() {
    msg::ClockProbe q;
    {
        std::lock_guard lock(mutex_);
        q.process(p_.process());
        q.probe(next_probe_++);
        if (asked_.size() >= kMaxOutstanding) asked_.erase(asked_.begin());
        const Nanos t1 = p_.clock().now_ns();
        asked_[q.probe()] = t1;
        q.header().stamp(to_msg(t1));
    }
    requests_.write(q);
}

std::optional<ClockEstimate> ClockClient::estimate() const {
    std::lock_guard lock(mutex_);
    return filter_.estimate();
}

}  // namespace dw::dds
