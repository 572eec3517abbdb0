#include "probe/probe.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <iomanip>
#include <memory>
#include <mutex>
#include <ostream>
#include <thread>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "dds/wire_enums.hpp"
#include "core/shutdown.hpp"
#include "dds/endpoint.hpp"
#include "dds/time.hpp"
#include "probe/samples.hpp"

namespace dw::probe {
namespace {
constexpr double kMinRate_hz = 0.01;  // slower rounds are a stuck publisher, not a rate
}  // namespace

namespace {

std::mutex g_out_mutex;

class PubChannel {
public:
    virtual ~PubChannel() = default;
    virtual const std::string& name() const = 0;
    virtual bool wait_for_readers(int n, std::chrono::milliseconds timeout) const = 0;
    virtual bool publish(std::uint64_t i) = 0;
    virtual bool wait_for_acknowledgments(std::chrono::milliseconds timeout) = 0;
    virtual std::string last_summary() const = 0;
};

template <class T>
class TypedPub final : public PubChannel {
public:
    TypedPub(dds::Participant& p, const dds::Topic<T>& spec, const dds::QosOverrides& q) : writer_(p, spec, q) {}
    const std::string& name() const override { return writer_.name(); }
    bool wait_for_readers(int n, std::chrono::milliseconds timeout) const override {
        return writer_.wait_for_readers(n, timeout);
    }
    bool publish(std::uint64_t i) override {
        sample_ = make_sample<T>(i);
        return writer_.write(sample_);
    }
    std::string last_summary() const override { return summary(sample_); }
    bool wait_for_acknowledgments(std::chrono::milliseconds timeout) override {
        return writer_.wait_for_acknowledgments(timeout);
    }

private:
    dds::Writer<T> writer_;
    T sample_;
};

class EchoChannel {
public:
    virtual ~EchoChannel() = default;
    virtual TopicResult result() const = 0;
};

template <class T>
class TypedEcho final : public EchoChannel {
public:
    TypedEcho(dds::Participant& p, const dds::Topic<T>& spec, const dds::QosOverrides& q, std::uint64_t expect,
              bool quiet, std::ostream& out)
        : expect_(expect),
          quiet_(quiet),
          out_(out),
          reader_(
              p, spec, [this](const T& m, const dds::SampleMeta&) { on_sample(m); }, q) {
        result_.topic = reader_.name();
        result_.type = std::string(spec.type_name);
        result_.qos = reader_.qos_text();
        result_.met = expect == 0;
    }
    TopicResult result() const override {
        std::lock_guard lock(mutex_);
        TopicResult r = result_;
        // Gaps are counted per writer over every sample, so real traffic does not inflate them.
        r.lost = reader_.lost();
        return r;
    }

private:
    void on_sample(const T& m) {
        if (m.header().run_id() != kProbeRunId) {
            // Real traffic (heartbeats, a running lab): shown, not checked.
            {
                std::lock_guard lock(mutex_);
                ++result_.other;
            }
            if (!quiet_) {
                std::lock_guard lock(g_out_mutex);
                out_ << reader_.name() << "  (lab) " << summary(m) << "\n";
            }
            return;
        }
        const std::uint64_t seq = m.header().seq();
        const bool intact = m == make_sample<T>(seq);
        {
            std::lock_guard lock(mutex_);
            if (result_.received == 0) result_.first_seq = seq;
            else if (seq <= result_.last_seq) result_.in_order = false;
            result_.last_seq = seq;
            ++result_.received;
            intact ? ++result_.intact : ++result_.corrupt;
            if (expect_ > 0 && result_.intact >= expect_) result_.met = true;
        }
        if (!quiet_ || !intact) {
            std::lock_guard lock(g_out_mutex);
            out_ << reader_.name() << "  #" << seq << "  " << summary(m)
                 << (intact ? "" : "  CORRUPT: differs from the sample sent") << "\n";
            out_.flush();
        }
    }

    std::uint64_t expect_;
    bool quiet_;
    std::ostream& out_;
    mutable std::mutex mutex_;
    TopicResult result_;
    dds::Reader<T> reader_;  // last: its callback uses the members above
};

template <class F>
void visit_selected(const std::vector<std::string>& selected, F&& f) {
    dds::topics::for_each([&](const auto& spec) {
        if (std::find(selected.begin(), selected.end(), std::string(spec.suffix)) != selected.end()) f(spec);
    });
}

}  // namespace

bool run_pub(dds::Participant& p, const PubOptions& o, std::ostream& out) {
    std::vector<std::unique_ptr<PubChannel>> channels;
    visit_selected(o.topics, [&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        channels.push_back(std::make_unique<TypedPub<T>>(p, spec, o.qos));
    });
    if (o.wait_readers > 0) {
        const auto deadline = std::chrono::steady_clock::now() + o.wait_timeout;
        for (const auto& c : channels) {
            const auto left =
                std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
            if (!c->wait_for_readers(o.wait_readers, std::max(left, std::chrono::milliseconds(0)))) {
                log::error("no reader on ", c->name(), " after ", std::chrono::duration<double>(o.wait_timeout).count(),
                           " s");
                return false;
            }
        }
    }
    if (o.rate_hz > 0 && o.rate_hz < kMinRate_hz) {
        throw InputError(
            log::cat("--rate: ", o.rate_hz, " Hz is below ", kMinRate_hz, " Hz (0 means as fast as possible)"));
    }
    const auto period = std::chrono::duration<double>(o.rate_hz > 0 ? 1.0 / o.rate_hz : 0.0);
    auto next = std::chrono::steady_clock::now();
    for (std::uint64_t i = 0; i < o.count && !o.stop.stop_requested(); ++i) {
        for (const auto& c : channels) {
            if (!c->publish(i)) log::warn("write failed on ", c->name(), " (sample ", i, ")");
            if (!o.quiet) out << c->name() << "  #" << i << "  " << c->last_summary() << "\n";
        }
        next += std::chrono::duration_cast<std::chrono::steady_clock::duration>(period);
        if (wait_for(o.stop, next - std::chrono::steady_clock::now())) break;  // a slow rate still stops at once
    }
    out.flush();
    for (const auto& c : channels) {
        if (!c->wait_for_acknowledgments(std::chrono::seconds(5)))
            log::warn("not every reader acknowledged ", c->name());
    }
    if (o.linger.count() < 0) {
        while (!wait_for(o.stop, std::chrono::seconds(1))) {}
    } else if (o.linger.count() > 0) {
        wait_for(o.stop, o.linger);
    }
    return true;
}

bool EchoReport::ok() const {
    if (timed_out) return false;
    return std::all_of(topics.begin(), topics.end(), [](const TopicResult& t) { return t.met && t.corrupt == 0; });
}

std::string EchoReport::to_json() const {
    nlohmann::json j;
    j["ok"] = ok();
    j["timed_out"] = timed_out;
    j["topics"] = nlohmann::json::array();
    for (const auto& t : topics) {
        j["topics"].push_back({{"topic", t.topic},
                               {"type", t.type},
                               {"qos", t.qos},
                               {"received", t.received},
                               {"other", t.other},
                               {"intact", t.intact},
                               {"corrupt", t.corrupt},
                               {"lost", t.lost},
                               {"first_seq", t.first_seq},
                               {"last_seq", t.last_seq},
                               {"in_order", t.in_order},
                               {"met", t.met}});
    }
    return j.dump(2);
}

EchoReport run_echo(dds::Participant& p, const EchoOptions& o, std::ostream& out) {
    std::vector<std::unique_ptr<EchoChannel>> channels;
    visit_selected(o.topics, [&](const auto& spec) {
        using T = typename std::decay_t<decltype(spec)>::type;
        const bool latched = spec.qos == dds::QosProfile::state;
        const std::uint64_t expect =
            latched && o.expect_latched >= 0 ? static_cast<std::uint64_t>(o.expect_latched) : o.expect;
        channels.push_back(std::make_unique<TypedEcho<T>>(p, spec, o.qos, expect, o.quiet, out));
    });
    EchoReport report;
    const auto start = std::chrono::steady_clock::now();
    const bool bounded = o.expect > 0 || o.expect_latched > 0;
    for (;;) {
        if (wait_for(o.stop, std::chrono::milliseconds(20))) break;
        if (bounded && std::all_of(channels.begin(), channels.end(), [](const auto& c) { return c->result().met; }))
            break;
        if (o.timeout.count() > 0 && std::chrono::steady_clock::now() - start >= o.timeout) {
            report.timed_out = true;
            break;
        }
    }
    for (const auto& c : channels) report.topics.push_back(c->result());
    return report;
}

void print_table(const EchoReport& report, std::ostream& out) {
    out << std::left << std::setw(30) << "topic" << std::setw(28) << "type" << std::right << std::setw(9) << "received"
        << std::setw(8) << "intact" << std::setw(8) << "corrupt" << std::setw(6) << "lost" << std::setw(7) << "other"
        << "  qos\n";
    for (const auto& t : report.topics) {
        out << std::left << std::setw(30) << t.topic << std::setw(28) << t.type << std::right << std::setw(9)
            << t.received << std::setw(8) << t.intact << std::setw(8) << t.corrupt << std::setw(6) << t.lost
            << std::setw(7) << t.other << "  " << t.qos << (t.met ? "" : "  (expected more)") << "\n";
    }
    out << (report.ok()        ? "all topics arrived intact"
            : report.timed_out ? "timed out before every topic arrived"
                               : "FAILED")
        << "\n";
}

void send_command(dds::Participant& p, const CommandOptions& o, std::ostream& out) {
    dds::Writer<msg::ExperimentCommand> w(p, dds::topics::experiment_command);
    const auto until = std::chrono::steady_clock::now() + o.wait;
    while (!p.unmatched_readers(w.matched_readers(), {o.to}).empty()) {
        if (std::chrono::steady_clock::now() >= until)
            throw RuntimeError(log::cat("no reader of ", w.name(), " from ", o.to, " within ", o.wait.count() / 1000.0,
                                        " s: is it running?"));
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    msg::ExperimentCommand c;
    c.header().stamp(dds::to_msg(p.clock().now_ns()));
    c.kind(o.kind);
    c.issuer(p.process());
    c.reason(o.reason);
    w.write(c);
    const bool acked = w.wait_for_acknowledgments(o.wait);
    out << "sent " << dds::command_name(o.kind) << " to " << w.matched() << " reader(s) of " << w.name()
        << (acked ? "" : " (not every reader acknowledged it)") << "\n";
}

}  // namespace dw::probe
