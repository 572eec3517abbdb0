#pragma once
// dw-recorder's record: every lab topic (or a filter) into MCAP — `omgidl` schemas (the IDL with
// includes resolved, named by the scoped type), `cdr` channels with their QoS in the metadata,
// log time = receive time, publish time = the writer's source timestamp. Chunks are flushed at
// least every flush interval (crash safety); files split by size or duration; pause/resume by
// experiment command or SIGUSR1; the run id comes from the experiment state; per-topic losses
// (gaps in the writers' sequence numbers) are shown live and stored in the file.
#include <atomic>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "dds/participant.hpp"
#include "mcap/mcap.hpp"

namespace dw::recorder {

struct RecordOptions {
    std::string out = "recording.mcap";  // file; with splitting, <stem>_NNNN.mcap
    std::vector<std::string> topics;     // suffixes; empty = all
    mcap::WriterOptions writer;
    std::uint64_t split_bytes = 0;                                 // 0 = no split by size
    double split_seconds = 0;                                      // 0 = no split by duration
    std::vector<std::pair<std::string, std::string>> attachments;  // name, path (read at start)
    bool start_paused = false;
    bool command_control = true;  // PAUSE/RESUME experiment commands pause/resume
    // Never overwrite: a file name already taken is skipped (the next <stem>_NNNN.mcap is used), and
    // a taken file left unfinished (its recorder was killed) is recovered in place, in the background.
    bool keep_existing = false;
};

// Samples a writer's header.seq says were sent but never arrived: the last sample of the topic
// before (0: none yet) and the one after, by receive time. Stored per file in the "gaps" metadata.
struct Gap {
    std::int64_t after_ns = 0, before_ns = 0;
    std::uint64_t missing = 0;
};
inline constexpr std::size_t kMaxGapsPerFile = 200;  // per topic; more are counted, not listed

// Received messages waiting for the file at most: beyond, they are dropped and counted (a disk
// stalled for minutes must not take the machine's memory).
inline constexpr std::size_t kMaxPendingBytes = 256u << 20;
// What the queue holds from the start, resident and reused (two of each: one filling while the
// other is written): ~9 s of the simulated lab's 0.23 MB/s and 1 400 messages/s. A queue that
// grew on each slow fdatasync and was freed after it left the recorder's memory rising in steps
// on a busy disk (dw-lab soak: 1.2 MB/min beside a writer of 400 MB files with fsync; a
// disk stall longer than this still grows it, once).
inline constexpr std::size_t kPendingReserveBytes = 2u << 20;
inline constexpr std::size_t kPendingReserveMessages = 12'000;

struct TopicStats {
    std::string topic;
    std::uint64_t recorded = 0;
    std::uint64_t lost = 0;     // gaps in the writers' header.seq
    std::uint64_t skipped = 0;  // arrived while paused
    std::uint64_t dropped = 0;  // arrived while kMaxPendingBytes waited for a stalled disk
};

class Recorder {
public:
    // Throws dw::InputError for a bad topic or attachment, dw::RuntimeError when the file fails.
    Recorder(dds::Participant& participant, const RecordOptions& options);
    ~Recorder();  // closes the file (a failure then is logged: close() first to see it)

    void pause(const std::string& why);
    void resume(const std::string& why);
    void toggle(const std::string& why);
    bool paused() const { return paused_; }
    // Periodic work from the owner's loop: flushes due chunks, splits files.
    void tick();
    void close();

    std::vector<TopicStats> stats() const;
    // Messages not recorded because kMaxPendingBytes were already waiting for a stalled disk
    // (every topic; each topic's share is in stats() and the file's loss metadata).
    std::uint64_t dropped() const;
    std::vector<std::string> files() const;
    std::string run_id() const;
    // One line for the live display: messages, rate, losses.
    std::string status_line();

    class Channel;  // one per topic, typed (recorder.cpp)

private:
    friend class Channel;
    void open_file();
    std::string path_for(std::size_t index) const;
    // Recovers each file in place (keep_existing: files a killed recorder left unfinished).
    void repair(std::vector<std::string> unfinished);
    void close_file();
    struct ChannelInfo {
        std::string topic, type, qos, qos_profile, idl;
    };
    // Schema and channel records of one topic in the current file; returns the channel id.
    std::uint16_t announce(const ChannelInfo& c);
    // Writes what the listeners queued (messages, metadata) into the file; mutex_ held.
    void drain_pending();
    void on_message(std::uint16_t channel_index, std::span<const std::uint8_t> cdr, std::uint64_t log_time,
                    std::uint64_t publish_time, std::uint32_t sequence);
    void note_run(const std::string& run_id);
    void note_plan(const std::string& name, const std::string& formation, const std::string& document);

    dds::Participant& participant_;
    RecordOptions options_;
    // Two locks, taken in this order: mutex_ guards the file (the owner's tick: compression, writes,
    // fdatasync); pending_mutex_ guards what DDS's listeners queue for it. A listener never waits on
    // the disk: a slow fdatasync once held the receive thread, losing samples and the recorder's own
    // heartbeat (found by dw-lab soak on a busy machine).
    mutable std::mutex mutex_;
    mutable std::mutex pending_mutex_;
    struct Pending {
        std::uint16_t index;
        std::uint32_t sequence;
        std::uint64_t log_time, publish_time;
        std::size_t offset, size;  // in its batch's data
    };
    struct Batch {
        std::vector<Pending> messages;
        std::string data;
        std::vector<mcap::Metadata> metadata;
        Batch();       // reserved and touched: resident from the start
        void clear();  // keeps the capacity
    };
    Batch pending_;   // filled by the listeners (pending_mutex_)
    Batch draining_;  // written to the file by the owner's tick (mutex_)
    std::uint64_t dropped_ = 0;
    std::unique_ptr<mcap::Writer> writer_;
    std::vector<std::string> files_;
    std::vector<std::pair<std::string, std::string>> attachment_data_;  // name, bytes
    std::vector<ChannelInfo> infos_;                                    // by channel index
    std::vector<std::uint16_t> channel_ids_;                            // in the current file, by channel index
    std::int64_t file_opened_ns_ = 0;
    std::size_t next_index_ = 0;           // of the next file name to try
    std::vector<std::string> unfinished_;  // found by open_file, handed to repair
    std::atomic<bool> paused_{false};
    std::string run_id_;     // pending_mutex_
    std::string last_plan_;  // pending_mutex_
    std::vector<std::unique_ptr<Channel>> channels_;
    std::uint64_t last_total_ = 0;
    std::int64_t last_status_ns_ = 0;
    std::jthread repairing_;  // last member: joined first
};

}  // namespace dw::recorder
