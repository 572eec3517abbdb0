#include "recorder/recorder.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "dds/cdr.hpp"
#include "dds/endpoint.hpp"
#include "idl/idl_texts.hpp"

namespace dw::recorder {

// One lab topic: a typed reader whose samples are serialised back to CDR (the bytes a DDS
// writer sends, encapsulation header first) and handed to the recorder. What the file says
// about the topic (name, type, QoS, IDL) is the recorder's ChannelInfo.
class Recorder::Channel {
public:
    virtual ~Channel() = default;
    virtual TopicStats stats() const = 0;
    // The gaps since the last call, as the "gaps" metadata's text: "after_s-before_s (silence s): N missing; ...".
    std::string take_gaps_text() {
        std::lock_guard lock(gaps_mutex_);
        std::ostringstream s;
        for (const auto& g : gaps_) {
            if (s.tellp() > 0) s << "; ";
            if (g.after_ns > 0)
                s << fixed(to_seconds(g.after_ns), 3) << "-" << fixed(to_seconds(g.before_ns), 3) << " ("
                  << fixed(to_seconds(g.before_ns - g.after_ns), 3) << " s)";
            else s << "before " << fixed(to_seconds(g.before_ns), 3);
            s << ": " << g.missing << " missing";
        }
        if (gaps_unlisted_ > 0) s << "; and " << gaps_unlisted_ << " more gaps";
        gaps_.clear();
        gaps_unlisted_ = 0;
        return s.str();
    }
    std::atomic<std::uint64_t> recorded{0}, skipped{0}, dropped{0};

protected:
    void note_gap(const Gap& g) {
        std::lock_guard lock(gaps_mutex_);
        if (gaps_.size() < kMaxGapsPerFile) gaps_.push_back(g);
        else ++gaps_unlisted_;
    }

private:
    std::mutex gaps_mutex_;
    std::vector<Gap> gaps_;
    std::uint64_t gaps_unlisted_ = 0;
};

namespace {

template <class T>
class TypedChannel final : public Recorder::Channel {
public:
    TypedChannel(
        dds::Participant& p, const dds::Topic<T>& spec, std::uint16_t index, std::function<void(const T&)> observe,
        std::function<void(std::uint16_t, std::span<const std::uint8_t>, std::uint64_t, std::uint64_t, std::uint32_t)>
            sink)
        : observe_(std::move(observe)),
          sink_(std::move(sink)),
          index_(index),
          reader_(p, spec, [this](const T& m, const dds::SampleMeta& meta) { on_sample(m, meta); }) {}
    TopicStats stats() const override {
        return {reader_.name(), recorded.load(), reader_.lost(), skipped.load(), dropped.load()};
    }

private:
    void on_sample(const T& m, const dds::SampleMeta& meta) {
        if (observe_) observe_(m);
        Nanos& last = last_received_ns_[meta.writer];  // per writer: its own silence, not the topic's
        if (meta.missing_before > 0) note_gap({last, meta.reception_time_ns, meta.missing_before});
        last = meta.reception_time_ns;
        const auto payload = cdr_.serialize(m);
        if (payload.empty()) return;
        sink_(index_, payload, static_cast<std::uint64_t>(meta.reception_time_ns),
              static_cast<std::uint64_t>(meta.source_time_ns), static_cast<std::uint32_t>(m.header().seq()));
    }

    std::function<void(const T&)> observe_;
    std::function<void(std::uint16_t, std::span<const std::uint8_t>, std::uint64_t, std::uint64_t, std::uint32_t)>
        sink_;
    std::uint16_t index_;
    std::map<eprosima::fastdds::dds::InstanceHandle_t, Nanos> last_received_ns_;  // per writer; listener thread only
    dds::CdrWriter<T> cdr_;
    dds::Reader<T> reader_;  // last: its callback uses the members above
};

std::string read_attachment(const std::string& path) { return dw::read_file(path, "--attach"); }

std::string hostname() {
    char buf[256] = {};
    ::gethostname(buf, sizeof(buf) - 1);
    return buf;
}

}  // namespace

Recorder::Recorder(dds::Participant& participant, const RecordOptions& options)
    : participant_(participant), options_(options) {
    for (const auto& [name, path] : options_.attachments) attachment_data_.emplace_back(name, read_attachment(path));
    paused_ = options_.start_paused;
    const auto& wanted = options_.topics;
    auto sink = [this](std::uint16_t i, std::span<const std::uint8_t> d, std::uint64_t lt, std::uint64_t pt,
                       std::uint32_t seq) { on_message(i, d, lt, pt, seq); };
    {
        std::lock_guard lock(mutex_);
        open_file();  // before the readers: a latched sample may arrive at once
    }
    if (!unfinished_.empty()) repairing_ = std::jthread([this, files = std::move(unfinished_)] { repair(files); });
    channels_.reserve(dds::topics::kTopicCount);
    channel_ids_.reserve(dds::topics::kTopicCount);
    dds::topics::for_each([&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        const bool take =
            wanted.empty() || std::find(wanted.begin(), wanted.end(), std::string(spec.suffix)) != wanted.end();
        if (!take) return;
        std::function<void(const T&)> observe;
        if constexpr (std::is_same_v<T, msg::ExperimentState>) {
            observe = [this](const T& s) { note_run(s.header().run_id()); };
        } else if constexpr (std::is_same_v<T, msg::ExperimentPlan>) {
            observe = [this](const T& p) { note_plan(p.name(), p.formation(), p.document()); };
        } else if constexpr (std::is_same_v<T, msg::ExperimentCommand>) {
            if (options_.command_control) {
                observe = [this](const T& c) {
                    if (c.kind() == msg::CMD_PAUSE) pause("PAUSE command from " + c.issuer());
                    if (c.kind() == msg::CMD_RESUME) resume("RESUME command from " + c.issuer());
                };
            }
        }
        const auto index = static_cast<std::uint16_t>(channel_ids_.size());
        {
            // Announced before the reader exists, so the first sample always has its channel.
            std::lock_guard lock(mutex_);
            infos_.push_back({participant_.topic_name(spec.suffix), std::string(spec.type_name),
                              dds::describe(dds::reader_qos(spec.qos)), dds::to_string(spec.qos),
                              std::string(spec.idl)});
            channel_ids_.push_back(announce(infos_.back()));
        }
        // No lock is held while the reader is created: its listener may already be running
        // (a latched sample) and Fast DDS must not wait on us.
        auto channel = std::make_unique<TypedChannel<T>>(participant_, spec, index, observe, sink);
        std::lock_guard lock(pending_mutex_);
        channels_.push_back(std::move(channel));
    });
}

Recorder::~Recorder() {
    if (writer_ && writer_->broken()) return;  // its write failed: said once, by whoever caught it
    try {
        close();
    } catch (const std::exception& e) {  // a destructor must not throw (a full disk, say): said, not thrown
        log::error("closing the recording failed: ", e.what());
    }
}

// File 0 is --out itself unless files split; file N is <stem>_NNNN.mcap.
std::string Recorder::path_for(std::size_t index) const {
    const bool split = options_.split_bytes > 0 || options_.split_seconds > 0;
    if (index == 0 && !split) return options_.out;
    const std::filesystem::path p(options_.out);
    char suffix[16];
    std::snprintf(suffix, sizeof(suffix), "_%04zu", index);
    return (p.parent_path() / (p.stem().string() + suffix + p.extension().string())).string();
}

void Recorder::repair(std::vector<std::string> unfinished) {
    for (const auto& path : unfinished) {
        try {
            const auto r = mcap::recover(path, path, options_.writer);
            log::info("recovered ", path, " (left unfinished by a recorder before this one): ", r.messages,
                      " messages");
        } catch (const std::exception& e) {
            log::warn("cannot recover ", path, ": ", e.what(), " (left as it is)");
        }
    }
}

void Recorder::open_file() {
    std::string path = path_for(next_index_++);
    while (options_.keep_existing && std::filesystem::exists(path)) {
        if (files_.empty() && !mcap::is_closed(path))
            unfinished_.push_back(path);  // the first file only: its predecessors'
        path = path_for(next_index_++);
    }
    writer_ = std::make_unique<mcap::Writer>(path, options_.writer);
    files_.push_back(path);
    file_opened_ns_ = participant_.clock().monotonic_ns();
    const auto& dds = participant_.config();
    writer_->add_metadata(
        {"recording",
         {{"host", hostname()},
          {"started_unix_ns", std::to_string(participant_.clock().now_ns())},
          {"recorder", "dw-recorder 0.1 (downwash-lab)"},
          {"fast_dds", "2.9 (Debian bookworm)"},
          {"dds_domain", std::to_string(dds.domain)},
          {"namespace", dds.ns},
          // Who recorded: the DDS Security identity (what it may read is its permissions).
          {"dds_security", dds.security.empty()
                               ? std::string("none")
                               : "identity " + (dds.identity.empty() ? participant_.process() : dds.identity)},
          {"file_index", std::to_string(next_index_ - 1)}}});
    for (const auto& [name, data] : attachment_data_) {
        const auto now = static_cast<std::uint64_t>(participant_.clock().now_ns());
        const std::string ext = std::filesystem::path(name).extension().string();
        const std::string media = ext == ".yaml" || ext == ".yml" ? "application/yaml"
                                  : ext == ".json"                ? "application/json"
                                                                  : "application/octet-stream";
        writer_->add_attachment({now, now, name, media, data});
    }
    // Re-announce what a split file needs (the first file gets its channels from the constructor).
    if (!infos_.empty()) {
        channel_ids_.clear();
        for (const auto& info : infos_) channel_ids_.push_back(announce(info));
        if (const std::string run = run_id(); !run.empty()) writer_->add_metadata({"run", {{"run_id", run}}});
    }
}

std::uint16_t Recorder::announce(const ChannelInfo& c) {
    const auto schema = writer_->add_schema(c.type, "omgidl", idl::resolved(c.idl));
    return writer_->add_channel(c.topic, schema, "cdr",
                                {{"qos", c.qos}, {"qos_profile", c.qos_profile}, {"dds_type", c.type}});
}

void Recorder::close_file() {
    if (!writer_) return;
    std::map<std::string, std::string> loss;
    for (const auto& c : channels_) {
        const TopicStats s = c->stats();
        loss[s.topic] = log::cat("recorded ", s.recorded, ", lost ", s.lost, ", skipped while paused ", s.skipped,
                                 ", dropped (disk stalled) ", s.dropped);
    }
    writer_->add_metadata({"loss", loss});
    std::map<std::string, std::string> gaps;
    for (const auto& c : channels_)
        if (auto text = c->take_gaps_text(); !text.empty()) gaps[c->stats().topic] = std::move(text);
    if (!gaps.empty()) writer_->add_metadata({"gaps", gaps});
    writer_->close();
    writer_.reset();
}

void Recorder::on_message(std::uint16_t index, std::span<const std::uint8_t> cdr, std::uint64_t log_time,
                          std::uint64_t publish_time, std::uint32_t sequence) {
    std::lock_guard lock(pending_mutex_);
    Channel* c = index < channels_.size() ? channels_[index].get() : nullptr;  // null while being set up
    if (paused_) {
        if (c) ++c->skipped;
        return;
    }
    if (pending_.data.size() + cdr.size() > kMaxPendingBytes) {
        ++dropped_;
        if (c) ++c->dropped;
        return;
    }
    pending_.messages.push_back({index, sequence, log_time, publish_time, pending_.data.size(), cdr.size()});
    pending_.data.append(reinterpret_cast<const char*>(cdr.data()), cdr.size());
}

Recorder::Batch::Batch() {
    messages.resize(kPendingReserveMessages);
    data.resize(kPendingReserveBytes);
    clear();
}

void Recorder::Batch::clear() {
    messages.clear();
    data.clear();
    metadata.clear();
}

void Recorder::drain_pending() {
    {
        std::lock_guard lock(pending_mutex_);
        std::swap(pending_, draining_);  // both keep their capacity: no allocation per tick
    }
    if (writer_) {
        for (const auto& m : draining_.metadata) writer_->add_metadata(m);
        const std::int64_t now = participant_.clock().monotonic_ns();
        const auto bytes =
            std::span(reinterpret_cast<const std::uint8_t*>(draining_.data.data()), draining_.data.size());
        for (const auto& m : draining_.messages) {
            writer_->write(
                {channel_ids_[m.index], m.sequence, m.log_time, m.publish_time, bytes.subspan(m.offset, m.size)}, now);
            if (m.index < channels_.size()) ++channels_[m.index]->recorded;
        }
    }
    draining_.clear();
}

void Recorder::note_run(const std::string& run_id) {
    std::lock_guard lock(pending_mutex_);
    if (run_id.empty() || run_id == run_id_) return;
    run_id_ = run_id;
    pending_.metadata.push_back(
        {"run", {{"run_id", run_id}, {"since_unix_ns", std::to_string(participant_.clock().now_ns())}}});
    log::info("run id ", run_id);
}

void Recorder::note_plan(const std::string& name, const std::string& formation, const std::string& document) {
    std::lock_guard lock(pending_mutex_);
    const std::string key = name + '\n' + formation + '\n' + document;
    if (key == last_plan_) return;  // latched plans are re-sent: store each plan once
    last_plan_ = key;
    pending_.metadata.push_back(
        {"experiment_plan", {{"name", name}, {"formation", formation}, {"document", document}}});
}

void Recorder::pause(const std::string& why) {
    if (!paused_.exchange(true)) log::info("paused (", why, ")");
}
void Recorder::resume(const std::string& why) {
    if (paused_.exchange(false)) log::info("resumed (", why, ")");
}
void Recorder::toggle(const std::string& why) { paused_ ? resume(why) : pause(why); }

void Recorder::tick() {
    std::lock_guard lock(mutex_);
    try {
        drain_pending();
        if (writer_) writer_->flush_if_due(participant_.clock().monotonic_ns());
    } catch (const RuntimeError& e) {  // a full disk: what was flushed before stays readable
        if (!writer_ || !writer_->broken()) throw;
        throw RuntimeError(log::cat(e.what(), " (the file keeps what was written before: dw-recorder recover ",
                                    writer_->path(), " OUT rebuilds it)"));
    }
    if (!writer_) return;
    const std::int64_t now = participant_.clock().monotonic_ns();
    const bool by_size = options_.split_bytes > 0 && writer_->bytes_written() >= options_.split_bytes;
    const bool by_time = options_.split_seconds > 0 && now - file_opened_ns_ >= from_seconds(options_.split_seconds);
    if (by_size || by_time) {
        close_file();
        open_file();
        log::info("split: now writing ", files_.back());
    }
}

void Recorder::close() {
    std::lock_guard lock(mutex_);
    drain_pending();
    close_file();
}

std::uint64_t Recorder::dropped() const {
    std::lock_guard lock(pending_mutex_);
    return dropped_;
}

std::vector<TopicStats> Recorder::stats() const {
    std::vector<TopicStats> out;
    for (const auto& c : channels_) out.push_back(c->stats());
    return out;
}

std::vector<std::string> Recorder::files() const {
    std::lock_guard lock(mutex_);
    return files_;
}

std::string Recorder::run_id() const {
    std::lock_guard lock(pending_mutex_);
    return run_id_;
}

std::string Recorder::status_line() {
    std::uint64_t total = 0, lost = 0;
    std::size_t active = 0;
    for (const auto& s : stats()) {
        total += s.recorded;
        lost += s.lost;
        if (s.recorded > 0) ++active;
    }
    const std::int64_t now = participant_.clock().monotonic_ns();
    const double dt = last_status_ns_ ? to_seconds(now - last_status_ns_) : 0.0;
    const double rate = dt > 0 ? static_cast<double>(total - last_total_) / dt : 0.0;
    last_total_ = total;
    last_status_ns_ = now;
    std::ostringstream out;
    out << (paused_ ? "PAUSED " : "recording ") << total << " messages on " << active << "/" << channels_.size()
        << " topics, " << static_cast<long>(rate) << " msg/s, lost " << lost;
    if (const auto d = dropped()) out << ", dropped " << d << " (disk stalled)";
    return out.str();
}

}  // namespace dw::recorder
