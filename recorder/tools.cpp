#include "recorder/tools.hpp"

#include <algorithm>
#include <optional>
#include <queue>
#include <tuple>
#include <map>
#include <memory>
#include <thread>

#include "core/errors.hpp"
#include "core/shutdown.hpp"
#include "core/log.hpp"
#include "dds/endpoint.hpp"
#include "mcap/mcap.hpp"
#include "recordings/recordings.hpp"

namespace dw::recorder {

namespace {
class ReplayChannel {
public:
    virtual ~ReplayChannel() = default;
    virtual bool publish(std::span<const std::uint8_t> cdr) = 0;
    virtual bool wait_for_readers(int n, std::chrono::milliseconds timeout) const = 0;
    virtual void wait_for_acknowledgments() = 0;
    virtual std::uint64_t refused() const = 0;
};
template <class T>
class TypedReplay final : public ReplayChannel {
public:
    TypedReplay(dds::Participant& p, const dds::Topic<T>& spec) : writer_(p, spec) {}
    bool publish(std::span<const std::uint8_t> cdr) override {
        if (!recordings::deserialize(cdr, sample_)) return false;
        return writer_.write_as_is(sample_);
    }
    bool wait_for_readers(int n, std::chrono::milliseconds timeout) const override {
        return writer_.wait_for_readers(n, timeout);
    }
    void wait_for_acknowledgments() override { writer_.wait_for_acknowledgments(std::chrono::seconds(5)); }
    std::uint64_t refused() const override { return writer_.refused(); }

private:
    dds::Writer<T> writer_;
    T sample_;
};
}  // namespace

namespace {
// Messages are published in log-time order within this window (a file may hold them slightly out
// of order across topics); the replay holds no more than the window's messages, whatever the
// recording's size.
constexpr std::uint64_t kReorderWindowNs = 500'000'000;

struct Pending {
    std::uint64_t log_time;
    std::uint64_t order;  // file order: equal times keep it
    std::uint16_t channel;
    std::vector<std::uint8_t> data;
    bool operator>(const Pending& o) const { return std::tie(log_time, order) > std::tie(o.log_time, o.order); }
};

// The writer replaying one recorded channel, or null when it is not replayed (a command topic
// without o.commands is noted in left_out).
std::unique_ptr<ReplayChannel> writer_for(const mcap::Channel& c, const std::string& type, dds::Participant& p,
                                          const ReplayOptions& o, std::vector<std::string>& left_out) {
    const std::string suffix = recordings::topic_suffix(c.topic);
    if (!o.topics.empty() && std::find(o.topics.begin(), o.topics.end(), suffix) == o.topics.end()) return nullptr;
    std::unique_ptr<ReplayChannel> w;
    dds::topics::for_each([&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        if (spec.suffix != suffix || spec.type_name != type) return;
        if (spec.command && !o.commands) left_out.emplace_back(suffix);
        else w = std::make_unique<TypedReplay<T>>(p, spec);
    });
    if (w && o.wait_readers > 0)
        while (!w->wait_for_readers(o.wait_readers, std::chrono::seconds(1)) && !o.stop.stop_requested()) {}
    return w;
}
}  // namespace

ReplayStats replay(const std::string& path, dds::Participant& p, const ReplayOptions& o) {
    ReplayStats stats;
    recordings::Catalogue l;
    std::map<std::uint16_t, std::unique_ptr<ReplayChannel>> writers;
    std::priority_queue<Pending, std::vector<Pending>, std::greater<>> pending;
    std::optional<std::chrono::steady_clock::time_point> start;
    std::uint64_t t0 = 0, newest = 0, order = 0, sent = 0;
    auto publish = [&](const Pending& it) {
        if (!start) start = std::chrono::steady_clock::now(), t0 = it.log_time;
        const auto offset = it.log_time > t0 ? it.log_time - t0 : 0;
        const auto due =
            *start + std::chrono::nanoseconds(static_cast<std::int64_t>(static_cast<double>(offset) / o.speed));
        // A recording's gap (an hour without samples) is waited out, but a stop ends the wait at once.
        if (dw::wait_for(o.stop, due - std::chrono::steady_clock::now())) throw Stopped("the replay");
        if (writers.at(it.channel)->publish(it.data)) ++sent;
    };
    mcap::Handlers h;
    l.watch(h);
    h.on_channel = [&](const mcap::Channel& c) {
        l.channels[c.id] = c;
        if (!writers.count(c.id)) writers[c.id] = writer_for(c, l.type_of(c), p, o, stats.left_out);
    };
    h.on_message = [&](const mcap::Message& m) {
        if (o.stop.stop_requested()) throw Stopped("the replay");
        const auto w = writers.find(m.channel_id);
        if (w == writers.end() || !w->second) return;
        newest = std::max(newest, m.log_time);
        pending.push({m.log_time, order++, m.channel_id, {m.data.begin(), m.data.end()}});
        while (!pending.empty() && pending.top().log_time + kReorderWindowNs < newest) {
            publish(pending.top());
            pending.pop();
        }
    };
    h.on_progress = [&](std::uint64_t done, std::uint64_t size) {
        if (o.progress) o.progress(static_cast<double>(done) / static_cast<double>(std::max<std::uint64_t>(size, 1)));
    };
    try {
        recordings::require_sound(mcap::read_file(path, h), path);
        for (; !pending.empty() && !o.stop.stop_requested(); pending.pop()) publish(pending.top());
    } catch (const Stopped&) {}
    if (std::none_of(writers.begin(), writers.end(), [](const auto& w) { return w.second != nullptr; }))
        throw InputError(log::cat(path, ": no recorded topic to replay",
                                  stats.left_out.empty() ? "" : " (command topics are replayed with --commands)"));
    for (const auto& [id, w] : writers) {
        if (!w) continue;
        w->wait_for_acknowledgments();
        stats.refused += w->refused();
    }
    if (o.progress) o.progress(1.0);
    stats.sent = sent;
    return stats;
}

}  // namespace dw::recorder
