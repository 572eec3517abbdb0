#pragma once
// Typed writer and reader over one lab topic. The topic's QoS profile comes from topics.hpp;
// an incompatible peer is reported through Participant::report_problem, never silent.
#include <fastdds/dds/publisher/DataWriter.hpp>
#include <fastdds/dds/publisher/DataWriterListener.hpp>
#include <fastdds/dds/subscriber/DataReader.hpp>
#include <fastdds/dds/subscriber/DataReaderListener.hpp>
#include <fastdds/dds/subscriber/SampleInfo.hpp>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <set>
#include <vector>
#include <condition_variable>
#include <functional>
#include <map>
#include <mutex>
#include <thread>

#include "core/errors.hpp"
#include "dds/msg_fields.hpp"
#include "dds/participant.hpp"

namespace dw::dds {

// After a writer sees a reader match, how long the reader may still be finishing its side: a
// best-effort sample written sooner can be lost.
inline constexpr std::chrono::milliseconds kMatchSettle{100};
// Best-effort samples are never acknowledged: a writer about to go away stays this long after its
// last sample so matched readers can take it (a process exiting at once lost its last sample,
// seen on a loaded 2-core machine: the reader had not yet taken it from shared memory).
inline constexpr std::chrono::milliseconds kBestEffortDrain{500};

namespace detail {
// Sequence numbers a writer may plausibly skip: kSeqSlack, plus kMaxSeqRate a second since its last
// sample arrived (no lab writer publishes at 100 kHz).
inline constexpr double kSeqSlack = 1000;
inline constexpr double kMaxSeqRate = 100'000;
// Under DDS Security the likely reason an endpoint is refused: the identity's permissions.
inline std::string denied_hint(const Participant& p, const char* verb) {
    if (p.config().security.empty()) return "";
    return " (under DDS Security: identity '" + (p.config().identity.empty() ? p.process() : p.config().identity) +
           "' may not " + verb + " it — its role's topics in dds/topics.hpp, its permissions in the keystore)";
}
// Waits until `count()` reaches n, or the timeout passes.
template <class F>
bool wait_until_count(F&& count, int n, std::chrono::milliseconds timeout) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (count() < n) {
        if (std::chrono::steady_clock::now() >= deadline) return false;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    return true;
}

// The QoS policies already reported by one endpoint (its listener runs on Fast DDS threads).
class ReportedPolicies {
public:
    bool first(std::uint32_t policy) {
        std::lock_guard lock(mutex_);
        return seen_.insert(policy).second;
    }

private:
    std::mutex mutex_;
    std::set<std::uint32_t> seen_;
};
}  // namespace detail

template <class T>
class Writer final : private eprosima::fastdds::dds::DataWriterListener {
public:
    Writer(Participant& p, const Topic<T>& spec, const QosOverrides& overrides = {})
        : participant_(p), spec_(spec), name_(p.topic_name(spec.suffix)), stats_(p.add_endpoint(name_, true)) {
        namespace fdds = eprosima::fastdds::dds;
        qos_ = writer_qos(spec.qos, overrides);
        writer_ = p.publisher().create_datawriter(&p.topic(spec), qos_, this,
                                                  fdds::StatusMask::publication_matched()
                                                      << fdds::StatusMask::offered_incompatible_qos());
        if (writer_ == nullptr)
            throw RuntimeError("cannot create a DDS writer on " + name_ + detail::denied_hint(p, "publish"));
    }
    ~Writer() override {
        writer_->set_listener(nullptr);
        participant_.publisher().delete_datawriter(writer_);
    }
    Writer(const Writer&) = delete;
    Writer& operator=(const Writer&) = delete;

    // Publishes the sample; its header.seq is set to this writer's next sequence number. On a
    // command topic a sample holding NaN or inf is not published (false, reported once).
    bool write(T& sample) {
        if (!sendable(sample)) return false;
        before_first_sample();
        sample.header().seq(next_seq_++);
        return counted(writer_->write(&sample));
    }

    // Publishes the sample exactly as given, header.seq included (replaying a recording).
    bool write_as_is(const T& sample) {
        if (!sendable(sample)) return false;
        before_first_sample();
        return counted(writer_->write(const_cast<T*>(&sample)));
    }

    // Holds the caller until the lab's required readers matched (once, bounded: DdsConfig).
    // write() does it before the first sample; a writer fed from a reader's callback calls it
    // before subscribing, so the wait never blocks Fast DDS's reception thread (the samples
    // arriving meanwhile would overflow that reader's history and be lost).
    bool await_readers() {
        before_first_sample();
        return readers_arrived_;
    }

    int matched() const { return matched_.load(); }
    // False when the first sample went out because awaiting the required readers timed out.
    bool awaited_readers_arrived() const { return readers_arrived_; }
    // The readers matched now (kept from the listener: Fast DDS 2.9.1 has no get_matched_subscriptions).
    std::vector<eprosima::fastdds::dds::InstanceHandle_t> matched_readers() {
        std::lock_guard lock(readers_mutex_);
        return matched_readers_;
    }
    // True once n readers matched. The writer sees a match before the reader has finished its
    // side, and best-effort samples sent in between are dropped, so this waits a little more.
    bool wait_for_readers(int n, std::chrono::milliseconds timeout) const {
        if (!detail::wait_until_count([this] { return matched(); }, n, timeout)) return false;
        std::this_thread::sleep_for(kMatchSettle);
        return true;
    }
    // Waits until every reliable reader acknowledged every sample (call before exiting, or the
    // last samples can die with the process). A best-effort writer with readers waits until
    // kBestEffortDrain after its last sample (at most timeout), the nearest it has to one; several
    // writers that stopped together wait that once.
    bool wait_for_acknowledgments(std::chrono::milliseconds timeout) {
        if (qos_.reliability().kind == eprosima::fastdds::dds::BEST_EFFORT_RELIABILITY_QOS) {
            if (matched() > 0)
                std::this_thread::sleep_until(
                    std::min(std::chrono::steady_clock::now() + timeout, last_sample_.load() + kBestEffortDrain));
            return true;
        }
        const eprosima::fastrtps::Duration_t d(static_cast<std::int32_t>(timeout.count() / 1000),
                                               static_cast<std::uint32_t>((timeout.count() % 1000) * 1'000'000));
        return writer_->wait_for_acknowledgments(d) == ReturnCode_t::RETCODE_OK;
    }
    const std::string& name() const { return name_; }
    const Topic<T>& spec() const { return spec_; }
    std::string qos_text() const { return describe(qos_); }
    eprosima::fastdds::dds::DataWriter& native() { return *writer_; }

    // Samples refused by write() and write_as_is(): NaN or inf on a command topic.
    std::uint64_t refused() const { return refused_; }

private:
    bool counted(bool ok) {
        (ok ? stats_->samples : stats_->lost).fetch_add(1, std::memory_order_relaxed);
        if (ok) last_sample_.store(std::chrono::steady_clock::now(), std::memory_order_relaxed);
        return ok;
    }
    bool sendable(const T& sample) {
        if (!spec_.command || all_finite(sample)) return true;
        if (refused_++ == 0)
            participant_.report_problem(name_ + ": a sample holding NaN or inf was not published (a command topic)");
        return false;
    }
    // A sensor topic's first sample waits for the lab's required readers (DdsConfig::await_readers):
    // best-effort samples sent before they match are lost to them.
    void before_first_sample() {
        if (awaited_) return;
        awaited_ = true;
        if (spec_.qos != QosProfile::sensor) return;
        readers_arrived_ = await_required_readers(
            participant_,
            [this] {
                std::lock_guard lock(readers_mutex_);
                return matched_readers_;
            },
            name_);
    }
    void on_publication_matched(eprosima::fastdds::dds::DataWriter*,
                                const eprosima::fastdds::dds::PublicationMatchedStatus& s) override {
        matched_ = s.current_count;
        std::lock_guard lock(readers_mutex_);
        auto& v = matched_readers_;
        if (s.current_count_change > 0) {
            v.push_back(s.last_subscription_handle);
        } else if (s.current_count_change < 0) {
            v.erase(std::remove(v.begin(), v.end(), s.last_subscription_handle), v.end());
        }
    }
    void on_offered_incompatible_qos(eprosima::fastdds::dds::DataWriter*,
                                     const eprosima::fastdds::dds::OfferedIncompatibleQosStatus& s) override {
        // One line per policy: Fast DDS may announce the same peer more than once.
        if (!reported_.first(s.last_policy_id)) return;
        participant_.report_problem(
            qos_mismatch_line(name_, spec_.type_name, false, describe(qos_), s.last_policy_id, s.total_count));
    }

    std::uint64_t refused_ = 0;
    // When the last sample went out (the epoch until then: nothing to drain).
    std::atomic<std::chrono::steady_clock::time_point> last_sample_{};
    detail::ReportedPolicies reported_;
    Participant& participant_;
    Topic<T> spec_;
    std::string name_;
    std::shared_ptr<EndpointStats> stats_;
    eprosima::fastdds::dds::DataWriterQos qos_;
    eprosima::fastdds::dds::DataWriter* writer_ = nullptr;
    std::atomic<int> matched_{0};
    std::uint64_t next_seq_ = 0;
    bool awaited_ = false;
    bool readers_arrived_ = true;
    std::mutex readers_mutex_;
    std::vector<eprosima::fastdds::dds::InstanceHandle_t> matched_readers_;  // from the listener
};

// What a reader knows about a sample besides its content.
struct SampleMeta {
    Nanos source_time_ns = 0;                         // the writer's DDS source timestamp
    Nanos reception_time_ns = 0;                      // when Fast DDS received it
    eprosima::fastdds::dds::InstanceHandle_t writer;  // which writer sent it
    std::uint64_t missing_before = 0;  // header.seq values of this writer skipped just before this sample
};

template <class T>
class Reader final : private eprosima::fastdds::dds::DataReaderListener {
public:
    using Callback = std::function<void(const T&, const SampleMeta&)>;
    using WriterGone = std::function<void(const eprosima::fastdds::dds::InstanceHandle_t&)>;

    // `on_sample` runs on a Fast DDS thread, one sample at a time.
    Reader(Participant& p, const Topic<T>& spec, Callback on_sample, const QosOverrides& overrides = {})
        : participant_(p),
          spec_(spec),
          name_(p.topic_name(spec.suffix)),
          stats_(p.add_endpoint(name_, false)),
          on_sample_(std::move(on_sample)) {
        namespace fdds = eprosima::fastdds::dds;
        qos_ = reader_qos(spec.qos, overrides);
        reader_ = p.subscriber().create_datareader(
            &p.topic(spec), qos_, this,
            fdds::StatusMask::data_available()
                << fdds::StatusMask::subscription_matched() << fdds::StatusMask::requested_incompatible_qos()
                << fdds::StatusMask::liveliness_changed() << fdds::StatusMask::sample_lost());
        if (reader_ == nullptr)
            throw RuntimeError("cannot create a DDS reader on " + name_ + detail::denied_hint(p, "subscribe to"));
    }
    ~Reader() override {
        reader_->set_listener(nullptr);
        participant_.subscriber().delete_datareader(reader_);
    }
    Reader(const Reader&) = delete;
    Reader& operator=(const Reader&) = delete;

    // Called when a writer unmatches or loses liveliness (a peer process vanished).
    void on_writer_gone(WriterGone f) {
        std::lock_guard lock(mutex_);
        on_writer_gone_ = std::move(f);
    }

    int matched() const { return matched_.load(); }
    bool wait_for_writers(int n, std::chrono::milliseconds timeout) const {
        return detail::wait_until_count([this] { return matched(); }, n, timeout);
    }
    std::uint64_t received() const { return stats_->samples.load(); }
    // Samples missing from the writers' header.seq sequences.
    std::uint64_t lost() const { return stats_->lost.load(); }
    const std::string& name() const { return name_; }
    const Topic<T>& spec() const { return spec_; }
    std::string qos_text() const { return describe(qos_); }

private:
    void on_data_available(eprosima::fastdds::dds::DataReader* reader) override {
        eprosima::fastdds::dds::SampleInfo info;
        while (reader->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
            if (!info.valid_data) continue;
            SampleMeta meta;
            meta.source_time_ns = info.source_timestamp.to_ns();
            meta.reception_time_ns = info.reception_timestamp.to_ns();
            meta.writer = info.publication_handle;
            if constexpr (requires(T & s) { s.header().seq(); }) {
                meta.missing_before = account(meta.writer, sample_.header().seq(), meta.reception_time_ns);
            } else {  // another system's type (PX4's): no sequence to account
                stats_->samples.fetch_add(1, std::memory_order_relaxed);
            }
            on_sample_(sample_, meta);
        }
    }
    void on_subscription_matched(eprosima::fastdds::dds::DataReader*,
                                 const eprosima::fastdds::dds::SubscriptionMatchedStatus& s) override {
        matched_ = s.current_count;
        if (s.current_count_change < 0) writer_gone(s.last_publication_handle);
    }
    void on_liveliness_changed(eprosima::fastdds::dds::DataReader*,
                               const eprosima::fastdds::dds::LivelinessChangedStatus& s) override {
        if (s.not_alive_count_change > 0) writer_gone(s.last_publication_handle);
    }
    void on_requested_incompatible_qos(eprosima::fastdds::dds::DataReader*,
                                       const eprosima::fastdds::dds::RequestedIncompatibleQosStatus& s) override {
        // One line per policy: Fast DDS may announce the same peer more than once.
        if (!reported_.first(s.last_policy_id)) return;
        participant_.report_problem(
            qos_mismatch_line(name_, spec_.type_name, true, describe(qos_), s.last_policy_id, s.total_count));
    }

    // Returns how many of the writer's sequence numbers were skipped before this one. A jump no
    // writer could have made since its last sample (more than kMaxSeqRate a second, kSeqSlack at
    // least) is a sequence number from a garbled sample (issue 70: a garbage word counted 1.8e19
    // samples lost), not a loss: it is not counted and does not move what comes next.
    std::uint64_t account(const eprosima::fastdds::dds::InstanceHandle_t& writer, std::uint64_t seq, Nanos now_ns) {
        stats_->samples.fetch_add(1, std::memory_order_relaxed);
        // Most topics have one writer: skip the map lookup while the writer stays the same.
        if (next_ == nullptr || !(last_writer_ == writer)) {
            auto [it, first] = next_seq_.try_emplace(writer, NextSeq{seq, now_ns});
            last_writer_ = writer;
            next_ = &it->second;
        }
        const double since_s = std::max(0.0, to_seconds(now_ns - next_->at_ns));
        const double plausible = detail::kSeqSlack + detail::kMaxSeqRate * since_s;
        const std::uint64_t missing = seq > next_->seq ? seq - next_->seq : 0;
        if (static_cast<double>(missing) > plausible) return 0;
        stats_->lost.fetch_add(missing, std::memory_order_relaxed);
        if (seq >= next_->seq) *next_ = {seq + 1, now_ns};
        return missing;
    }
    void writer_gone(const eprosima::fastdds::dds::InstanceHandle_t& handle) {
        WriterGone f;
        {
            std::lock_guard lock(mutex_);
            f = on_writer_gone_;
        }
        if (f) f(handle);
    }

    detail::ReportedPolicies reported_;
    Participant& participant_;
    Topic<T> spec_;
    std::string name_;
    std::shared_ptr<EndpointStats> stats_;
    Callback on_sample_;
    eprosima::fastdds::dds::DataReaderQos qos_;
    eprosima::fastdds::dds::DataReader* reader_ = nullptr;
    T sample_;  // reused: take_next_sample fills it, no allocation per sample for fixed types
    std::atomic<int> matched_{0};
    // Next expected header.seq per writer; listener thread only.
    struct NextSeq {
        std::uint64_t seq = 0;  // the header.seq expected next
        Nanos at_ns = 0;        // when the last counted one arrived
    };
    std::map<eprosima::fastdds::dds::InstanceHandle_t, NextSeq> next_seq_;
    eprosima::fastdds::dds::InstanceHandle_t last_writer_;
    NextSeq* next_ = nullptr;
    std::mutex mutex_;
    WriterGone on_writer_gone_;
};

}  // namespace dw::dds
