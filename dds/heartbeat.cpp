#include "dds/heartbeat.hpp"

#include <unistd.h>

#include <algorithm>
#include <string_view>

#include "core/log.hpp"
#include "dds/time.hpp"

namespace dw::dds {
namespace {
std::string hostname() {
    char buf[256] = {};
    if (::gethostname(buf, sizeof(buf) - 1) != 0) return "unknown";
    return buf;
}

std::uint64_t handle_key(const eprosima::fastdds::dds::InstanceHandle_t& h) {
    // A hash of the whole GUID (prefix + entity id): writers of different processes differ.
    std::string bytes(16, '\0');
    for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<char>(h.value[i]);
    return std::hash<std::string>{}(bytes);
}
}  // namespace

Heartbeat::Heartbeat(Participant& p, std::chrono::milliseconds period)
    : participant_(p), period_(period), writer_(p, topics::process_status), clock_(p), host_(hostname()) {
    last_snapshot_ns_ = p.clock().monotonic_ns();
    publish_now();  // peers hear of us at once; the thread publishes every period after this
    thread_ = std::thread([this] { loop(); });
}

Heartbeat::~Heartbeat() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
        state_ = msg::PROC_STOPPING;
    }
    cv_.notify_all();
    thread_.join();
    publish_now();
}

void Heartbeat::set_state(msg::ProcessState state, std::string message) {
    {
        std::lock_guard lock(mutex_);
        state_ = state;
        message_ = std::move(message);
    }
    publish_now();
}

void Heartbeat::set_run_id(std::string run_id) {
    std::lock_guard lock(mutex_);
    run_id_ = std::move(run_id);
}

msg::ProcessStatus Heartbeat::snapshot() {
    std::lock_guard lock(mutex_);
    const Nanos now_mono = participant_.clock().monotonic_ns();
    const double dt = to_seconds(now_mono - last_snapshot_ns_);
    last_snapshot_ns_ = now_mono;
    msg::ProcessStatus s;
    s.header().stamp(to_msg(participant_.clock().now_ns()));
    s.header().run_id(run_id_);
    s.process(participant_.process());
    s.host(host_);
    s.pid(static_cast<std::int32_t>(::getpid()));
    s.state(state_);
    s.period_s(std::chrono::duration<double>(period_).count());
    s.error_count(participant_.problem_count());
    s.message(message_);
    const auto clock = clock_.estimate();
    s.clock_offset_s(clock ? clock->offset_s : 0.0);
    s.clock_uncertainty_s(clock ? clock->uncertainty_s : -1.0);
    for (const auto& ep : participant_.endpoints()) {
        // Not our own heartbeat, nor the clock service's probes: the rates are the process's work.
        const bool service = (ep->topic == writer_.name() && ep->outgoing) ||
                             ep->topic == participant_.topic_name(topics::clock_request.suffix) ||
                             ep->topic == participant_.topic_name(topics::clock_reply.suffix);
        if (service) continue;
        msg::TopicRate r;
        r.topic(ep->topic);
        r.outgoing(ep->outgoing);
        const std::uint64_t n = ep->samples.load();
        std::uint64_t& prev = last_samples_[ep.get()];
        r.rate_hz(dt > 0 ? static_cast<double>(n - prev) / dt : 0.0);
        prev = n;
        r.samples(n);
        r.lost(ep->lost.load());
        s.rates().push_back(std::move(r));
    }
    return s;
}

void Heartbeat::publish_now() {
    msg::ProcessStatus s = snapshot();
    writer_.write(s);
}

void Heartbeat::loop() {
    std::unique_lock lock(mutex_);
    while (!cv_.wait_for(lock, period_, [this] { return stop_; })) {
        lock.unlock();
        clock_.ask();
        publish_now();
        lock.lock();
    }
}

std::optional<PeerEvent> PeerTable::observe(const msg::ProcessStatus& status, std::uint64_t writer_key, Nanos now) {
    Peer& peer = peers_[status.process()];
    const bool was_alive = peer.alive;
    peer.status = status;
    peer.last_seen = now;
    peer.writer_key = writer_key;
    if (status.state() == msg::PROC_STOPPING) {
        peer.alive = false;
        if (was_alive) return PeerEvent{PeerEvent::Kind::lost, status.process(), "stopped"};
        return std::nullopt;
    }
    peer.alive = true;
    if (!was_alive) {
        return PeerEvent{PeerEvent::Kind::appeared, status.process(),
                         log::cat("on ", status.host(), ", pid ", status.pid())};
    }
    return std::nullopt;
}

std::optional<PeerEvent> PeerTable::writer_gone(std::uint64_t writer_key, const std::string& why) {
    std::optional<PeerEvent> out;
    peers_.for_each([&](const std::string& name, Peer& peer) {
        if (out || !peer.alive || peer.writer_key != writer_key) return;
        peer.alive = false;
        out = PeerEvent{PeerEvent::Kind::lost, name, why};
    });
    return out;
}

std::vector<PeerEvent> PeerTable::expire(Nanos now) {
    std::vector<PeerEvent> out;
    peers_.for_each([&](const std::string& name, Peer& peer) {
        const Nanos limit = from_seconds(3.0 * peer.status.period_s());
        if (peer.alive && now - peer.last_seen > limit) {
            peer.alive = false;
            out.push_back(
                {PeerEvent::Kind::lost, name, log::cat("no heartbeat for ", to_seconds(now - peer.last_seen), " s")});
        }
    });
    return out;
}

std::vector<std::string> PeerTable::alive() const {
    std::vector<std::string> out;
    peers_.for_each([&](const std::string& name, const Peer& peer) {
        if (peer.alive) out.push_back(name);
    });
    return out;
}

std::optional<msg::ProcessStatus> PeerTable::last(const std::string& process) const {
    const Peer* peer = peers_.find(process);
    if (!peer) return std::nullopt;
    return peer->status;
}

PeerMonitor::PeerMonitor(Participant& p, Handler on_event)
    : participant_(p),
      on_event_(std::move(on_event)),
      reader_(p, topics::process_status, [this](const msg::ProcessStatus& s, const SampleMeta& meta) {
          std::optional<PeerEvent> e;
          const std::string identity = participant_.identity_of(meta.writer);
          {
              std::lock_guard lock(mutex_);
              e = table_.observe(s, handle_key(meta.writer), participant_.clock().monotonic_ns());
              identities_[s.process()] = identity;
          }
          emit(e);
      }) {
    reader_.on_writer_gone([this](const eprosima::fastdds::dds::InstanceHandle_t& h) {
        std::optional<PeerEvent> e;
        {
            std::lock_guard lock(mutex_);
            e = table_.writer_gone(handle_key(h), "left the domain");
        }
        emit(e);
    });
    thread_ = std::thread([this] { loop(); });
}

PeerMonitor::~PeerMonitor() {
    {
        std::lock_guard lock(mutex_);
        stop_ = true;
    }
    cv_.notify_all();
    thread_.join();
}

void PeerMonitor::emit(const std::optional<PeerEvent>& e) {
    if (!e) return;
    if (e->kind == PeerEvent::Kind::appeared) {
        log::info("peer ", e->process, " appeared (", e->reason, ")");
    } else {
        log::warn("peer ", e->process, " lost: ", e->reason);
    }
    if (on_event_) on_event_(*e);
}

void PeerMonitor::loop() {
    std::unique_lock lock(mutex_);
    while (!cv_.wait_for(lock, std::chrono::milliseconds(100), [this] { return stop_; })) {
        auto events = table_.expire(participant_.clock().monotonic_ns());
        lock.unlock();
        for (const auto& e : events) emit(e);
        lock.lock();
    }
}

std::vector<std::string> PeerMonitor::alive() const {
    std::lock_guard lock(mutex_);
    return table_.alive();
}

std::optional<msg::ProcessStatus> PeerMonitor::last(const std::string& process) const {
    std::lock_guard lock(mutex_);
    return table_.last(process);
}

std::string PeerMonitor::identity(const std::string& process) const {
    std::lock_guard lock(mutex_);
    const std::string* identity = identities_.find(process);
    return identity ? *identity : std::string();
}

bool PeerMonitor::wait_for(const std::vector<std::string>& processes, std::chrono::milliseconds timeout,
                           const std::stop_token& stop) const {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
        const auto up = alive();
        bool all = true;
        for (const auto& p : processes) {
            if (std::find(up.begin(), up.end(), p) == up.end()) all = false;
        }
        if (all) return true;
        if (std::chrono::steady_clock::now() >= deadline || stop.stop_requested()) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
}

}  // namespace dw::dds
