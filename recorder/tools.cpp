#include "recorder/tools.hpp"

#include <algorithm>
#include <map>
#include <memory>
#include <thread>

#include "core/errors.hpp"
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
};
template <class T>
class TypedReplay final : public ReplayChannel {
public:
    TypedReplay(dds::Participant& p, const dds::Topic<T>& spec) : writer_(p, spec) {}
    bool publish(std::span<const std::uint8_t> cdr) override {
        if (!recordings::deserialize(cdr, sample_)) return false;
        return writer_.write_as_is(sample_);
    }
    bool wait_for_readers(int n, std::chrono::milliseconds timeout) const override { return writer_.wait_for_readers(n, timeout); }
    void wait_for_acknowledgments() override { writer_.wait_for_acknowledgments(std::chrono::seconds(5)); }

private:
    dds::Writer<T> writer_;
    T sample_;
};
}  // namespace

std::uint64_t replay(const std::string& path, dds::Participant& p, const ReplayOptions& o) {
    recordings::Catalogue l;
    struct Item {
        std::uint64_t log_time;
        std::uint16_t channel;
        std::vector<std::uint8_t> data;
    };
    std::vector<Item> items;
    mcap::Handlers h;
    l.watch(h);
    h.on_message = [&](const mcap::Message& m) { items.push_back({m.log_time, m.channel_id, {m.data.begin(), m.data.end()}}); };
    recordings::require_sound(mcap::read_file(path, h), path);
    std::stable_sort(items.begin(), items.end(), [](const Item& a, const Item& b) { return a.log_time < b.log_time; });

    std::map<std::uint16_t, std::unique_ptr<ReplayChannel>> writers;
    for (const auto& [id, c] : l.channels) {
        const std::string suffix = recordings::topic_suffix(c.topic);
        if (!o.topics.empty() && std::find(o.topics.begin(), o.topics.end(), suffix) == o.topics.end()) continue;
        const std::string type = l.type_of(c);
        dds::topics::for_each([&](const auto& spec) {
            using T = typename std::decay_t<decltype(spec)>::type;
            if (spec.suffix == suffix && spec.type_name == type) writers[id] = std::make_unique<TypedReplay<T>>(p, spec);
        });
    }
    if (writers.empty()) throw InputError(log::cat(path, ": no recorded topic to replay"));
    if (o.wait_readers > 0) {
        for (const auto& [id, w] : writers) {
            while (!w->wait_for_readers(o.wait_readers, std::chrono::seconds(1)) && !o.stop.stop_requested()) {}
        }
    }
    const auto start = std::chrono::steady_clock::now();
    const std::uint64_t t0 = items.empty() ? 0 : items.front().log_time;
    std::uint64_t sent = 0;
    for (std::size_t i = 0; i < items.size() && !o.stop.stop_requested(); ++i) {
        const Item& it = items[i];
        auto w = writers.find(it.channel);
        if (w == writers.end()) continue;
        const auto due = start + std::chrono::nanoseconds(static_cast<std::int64_t>(static_cast<double>(it.log_time - t0) / o.speed));
        std::this_thread::sleep_until(due);
        if (w->second->publish(it.data)) ++sent;
        if (o.progress && i % 256 == 0) o.progress(static_cast<double>(i) / static_cast<double>(items.size()));
    }
    for (const auto& [id, w] : writers) w->wait_for_acknowledgments();
    if (o.progress) o.progress(1.0);
    return sent;
}

}  // namespace dw::recorder
