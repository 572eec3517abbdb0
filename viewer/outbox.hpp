#pragma once
// One client's frames waiting to be written, bounded (issue 72): a slow or stalled client loses
// its oldest stream frames (sensor samples, commands) and is told so, never delays the lab or the
// other clients; state topics keep only their latest frame per instance, so a lagging client
// still shows the truth. Thread-safe: DDS threads push, the client's writer pops.
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

namespace dw::viewer {

// At most this many stream frames, and this many bytes of them, wait per client.
inline constexpr std::size_t kMaxQueuedFrames = 1024;
inline constexpr std::size_t kMaxQueuedBytes = std::size_t{4} << 20;
// At most this many state instances are held (per client, and in the hub): names come from the
// wire, and a writer inventing one per sample must not grow memory. Past it a new instance's
// frame waits as a stream frame (bounded above).
inline constexpr std::size_t kMaxHeldStates = 512;

struct Frame {
    bool binary = false;
    std::string bytes;
};

class Outbox {
public:
    void push_stream(Frame f);
    // Replaces what waits for (channel, key): a state topic's newest sample per instance.
    void push_latest(std::uint32_t channel, const std::string& key, Frame f);
    // The next frame to write: a state frame first, then the oldest stream frame.
    std::optional<Frame> pop();
    std::uint64_t dropped() const;
    // Stream frames dropped since the last call (to tell the client), then 0.
    std::uint64_t take_new_drops();
    std::size_t bytes() const;

private:
    mutable std::mutex mutex_;
    std::deque<Frame> stream_;
    std::map<std::pair<std::uint32_t, std::string>, Frame> latest_;
    std::size_t bytes_ = 0;  // of stream_ and latest_
    std::uint64_t dropped_ = 0, new_drops_ = 0;
};

}  // namespace dw::viewer
