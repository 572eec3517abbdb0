#pragma once
// Heartbeats: every lab process publishes its ProcessStatus periodically, with its clock's offset
// from the reference (dds/clock_sync.hpp); a PeerMonitor notices
// peers that appear, and peers that vanish (writer unmatched or liveliness lost: at once; silent:
// after 3 heartbeat periods).
#include <chrono>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <stop_token>
#include <string>
#include <thread>
#include <vector>

#include "core/bounded_map.hpp"
#include "dds/clock_sync.hpp"
#include "dds/endpoint.hpp"

namespace dw::dds {

class Heartbeat {
public:
    explicit Heartbeat(Participant& p, std::chrono::milliseconds period = std::chrono::milliseconds(500));
    // Publishes a last PROC_STOPPING status, then stops.
    ~Heartbeat();
    Heartbeat(const Heartbeat&) = delete;
    Heartbeat& operator=(const Heartbeat&) = delete;

    void set_state(msg::ProcessState state, std::string message = "");
    void set_run_id(std::string run_id);
    // The status the next heartbeat will carry; rates are over the time since the last call.
    msg::ProcessStatus snapshot();
    void publish_now();

private:
    void loop();

    Participant& participant_;
    std::chrono::milliseconds period_;
    Writer<msg::ProcessStatus> writer_;
    ClockClient clock_;  // asks the reference clock every period; its estimate rides on the status
    std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
    msg::ProcessState state_ = msg::PROC_STARTING;
    std::string message_;
    std::string run_id_;
    std::string host_;
    std::map<const EndpointStats*, std::uint64_t> last_samples_;
    Nanos last_snapshot_ns_ = 0;
    std::thread thread_;
};

struct PeerEvent {
    enum class Kind { appeared, lost };
    Kind kind;
    std::string process;
    std::string reason;
};

// Processes a heartbeat table remembers: a lab runs a dozen; a writer inventing process names
// every heartbeat makes the least recently heard forgotten, never memory without bound.
inline constexpr std::size_t kMaxPeers = kMaxInstances;  // the heartbeat topic's instances (dds/qos.hpp)

// The peer bookkeeping, apart from DDS so it can be driven by tests with a manual clock.
class PeerTable {
public:
    // A status arrived at monotonic time now; returns an `appeared` event for a new/returning peer.
    std::optional<PeerEvent> observe(const msg::ProcessStatus& status, std::uint64_t writer_key, Nanos now);
    // The writer behind writer_key is gone (unmatched, liveliness lost).
    std::optional<PeerEvent> writer_gone(std::uint64_t writer_key, const std::string& why);
    // Peers silent for more than 3 of their own heartbeat periods.
    std::vector<PeerEvent> expire(Nanos now);
    // A status saying the process is stopping ends it at once.
    std::vector<std::string> alive() const;
    std::optional<msg::ProcessStatus> last(const std::string& process) const;

private:
    struct Peer {
        msg::ProcessStatus status;
        Nanos last_seen = 0;
        std::uint64_t writer_key = 0;
        bool alive = false;
    };
    BoundedMap<std::string, Peer> peers_{kMaxPeers};
};

class PeerMonitor {
public:
    using Handler = std::function<void(const PeerEvent&)>;
    // Checks for silent peers on its own thread every 100 ms; `on_event` may be empty.
    PeerMonitor(Participant& p, Handler on_event = {});
    ~PeerMonitor();
    PeerMonitor(const PeerMonitor&) = delete;
    PeerMonitor& operator=(const PeerMonitor&) = delete;

    std::vector<std::string> alive() const;
    std::optional<msg::ProcessStatus> last(const std::string& process) const;
    // Under DDS Security, the identity that sent the process's last heartbeat (its participant's
    // certificate common name); "" without DDS Security or before its participant is discovered.
    std::string identity(const std::string& process) const;
    // True once every named process has been heard from (and is still alive).
    bool wait_for(const std::vector<std::string>& processes, std::chrono::milliseconds timeout,
                  const std::stop_token& stop = {}) const;  // false also when stop is requested

private:
    void emit(const std::optional<PeerEvent>& e);
    void loop();

    Participant& participant_;
    Handler on_event_;
    mutable std::mutex mutex_;
    std::condition_variable cv_;
    bool stop_ = false;
    PeerTable table_;
    BoundedMap<std::string, std::string> identities_{kMaxPeers};  // process -> identity of its last heartbeat
    Reader<msg::ProcessStatus> reader_;
    std::thread thread_;
};

}  // namespace dw::dds
