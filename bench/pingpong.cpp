// dw-bench-pingpong: round-trip latency through the lab's DDS layer (dw::dds::Writer/Reader)
// and through raw Fast DDS (DataWriter/DataReader + listener), in the same run, with the same
// participant QoS, topic QoS and message (dw::msg::WrenchStamped). The echo side runs in a
// separate process, as the lab's processes do. Rounds alternate raw/layer so machine noise
// falls on both alike.
//
//   dw-bench-pingpong [--transport shm|udp|default] [--rounds 10] [--per-round 2000]
#include <fastdds/dds/domain/DomainParticipantFactory.hpp>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <iostream>
#include <numeric>

#include "dds/process_cli.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/subprocess.hpp"
#include "bench/raw_dds.hpp"
#include "dds/endpoint.hpp"

namespace fdds = eprosima::fastdds::dds;
using Msg = dw::msg::WrenchStamped;
using namespace std::chrono_literals;

namespace {

constexpr dw::dds::Topic<Msg> kLayerPing{"bench/layer/ping", dw::dds::QosProfile::command, "dw::msg::WrenchStamped",
                                         ""};
constexpr dw::dds::Topic<Msg> kLayerPong{"bench/layer/pong", dw::dds::QosProfile::command, "dw::msg::WrenchStamped",
                                         ""};
constexpr dw::dds::Topic<Msg> kRawPing{"bench/raw/ping", dw::dds::QosProfile::command, "dw::msg::WrenchStamped", ""};
constexpr dw::dds::Topic<Msg> kRawPong{"bench/raw/pong", dw::dds::QosProfile::command, "dw::msg::WrenchStamped", ""};

// --- raw Fast DDS: what a process would write without the layer ----------------------------
class RawEndpoint : public fdds::DataReaderListener {
public:
    RawEndpoint(const dw::dds::DdsConfig& cfg, const std::string& out_topic, const std::string& in_topic,
                std::function<void(const Msg&)> on_sample)
        : on_sample_(std::move(on_sample)), participant_(cfg, "raw") {
        writer_ = participant_.publisher()->create_datawriter(participant_.topic(out_topic),
                                                              dw::dds::writer_qos(dw::dds::QosProfile::command));
        reader_ = participant_.subscriber()->create_datareader(participant_.topic(in_topic),
                                                               dw::dds::reader_qos(dw::dds::QosProfile::command), this);
    }
    ~RawEndpoint() override { reader_->set_listener(nullptr); }
    void on_data_available(fdds::DataReader* r) override {
        fdds::SampleInfo info;
        while (r->take_next_sample(&sample_, &info) == ReturnCode_t::RETCODE_OK) {
            if (info.valid_data) on_sample_(sample_);
        }
    }
    void on_publication_matched(fdds::DataWriter*, const fdds::PublicationMatchedStatus&) {}
    bool write(Msg& m) { return writer_->write(&m); }
    bool matched() {
        fdds::PublicationMatchedStatus s;
        writer_->get_publication_matched_status(s);
        return s.current_count > 0;
    }

private:
    std::function<void(const Msg&)> on_sample_;
    dw::bench::RawParticipant participant_;
    fdds::DataWriter* writer_ = nullptr;
    fdds::DataReader* reader_ = nullptr;
    Msg sample_;
};

// --- the lab's layer ---------------------------------------------------------------------------
class LayerEndpoint {
public:
    LayerEndpoint(const dw::dds::DdsConfig& cfg, const dw::dds::Topic<Msg>& out, const dw::dds::Topic<Msg>& in,
                  std::function<void(const Msg&)> on_sample)
        : participant_(cfg, "layer"),
          writer_(participant_, out),
          reader_(participant_, in, [f = std::move(on_sample)](const Msg& m, const dw::dds::SampleMeta&) { f(m); }) {}
    bool write(Msg& m) { return writer_.write(m); }
    bool matched() { return writer_.matched() > 0; }

private:
    dw::dds::Participant participant_;
    dw::dds::Writer<Msg> writer_;
    dw::dds::Reader<Msg> reader_;
};

// Both endpoints expose write/matched; the pinger waits on an atomic the listener bumps.
template <class E>
struct Pinger {
    std::atomic<std::uint64_t> replies{0};
    std::unique_ptr<E> endpoint;

    std::vector<double> run(std::size_t n) {
        std::vector<double> rtt_us;
        rtt_us.reserve(n);
        Msg m;
        for (std::size_t i = 0; i < n; ++i) {
            const std::uint64_t before = replies.load();
            const auto t0 = std::chrono::steady_clock::now();
            m.force_n().x(static_cast<double>(i));
            endpoint->write(m);
            const auto deadline = t0 + 1s;
            while (replies.load() == before) {
                if (std::chrono::steady_clock::now() > deadline) throw dw::RuntimeError("no reply within 1 s");
            }
            rtt_us.push_back(std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - t0).count());
        }
        return rtt_us;
    }
};

double percentile(std::vector<double> v, double p) {
    std::sort(v.begin(), v.end());
    const auto idx = static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size() - 1));
    return v[idx];
}

template <class E>
bool wait_matched(E& e) {
    for (int i = 0; i < 3000; ++i) {
        if (e.matched()) return true;
        std::this_thread::sleep_for(10ms);
    }
    return false;
}

int run_pong(const dw::dds::DdsConfig& cfg) {
    // Echo every ping straight back, for both stacks at once.
    std::unique_ptr<RawEndpoint> raw;
    std::unique_ptr<LayerEndpoint> layer;
    Msg reply;
    std::mutex m;
    raw = std::make_unique<RawEndpoint>(cfg, "rt/" + cfg.ns + "/bench/raw/pong", "rt/" + cfg.ns + "/bench/raw/ping",
                                        [&](const Msg& in) {
                                            std::lock_guard l(m);
                                            reply = in;
                                            raw->write(reply);
                                        });
    layer = std::make_unique<LayerEndpoint>(cfg, kLayerPong, kLayerPing, [&](const Msg& in) {
        std::lock_guard l(m);
        reply = in;
        layer->write(reply);
    });
    while (!dw::Shutdown::instance().wait_for(1s)) {}
    return 0;
}

int run(int argc, char** argv) {
    dw::Shutdown::install();
    dw::dds::ProcessCli cli("dw-bench-pingpong: DDS round-trip latency, lab layer vs raw Fast DDS");
    CLI::App& app = cli.app();
    bool pong = false;
    int rounds = 10;
    std::size_t per_round = 2000;
    app.add_flag("--pong", pong, "(internal) run the echo side");
    app.add_option("--rounds", rounds, "alternating raw/layer rounds")->check(dw::cli::in({1, 1000}));
    app.add_option("--per-round", per_round, "round trips per round")->check(dw::cli::in({10, 1e6}));
    cli.parse(argc, argv);
    dw::dds::DdsConfig cfg = cli.dds();
    if (pong) return run_pong(cfg);
    // A namespace of its own, so a running lab on the same domain is not disturbed.
    if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "bench" + std::to_string(::getpid());

    std::vector<std::string> args{dw::executable_dir() + "/dw-bench-pingpong", "--pong"};
    for (const auto& a : dw::dds::to_args(cfg)) args.push_back(a);
    dw::Subprocess ponger({args, "", "", {}});

    Pinger<RawEndpoint> raw;
    raw.endpoint =
        std::make_unique<RawEndpoint>(cfg, "rt/" + cfg.ns + "/bench/raw/ping", "rt/" + cfg.ns + "/bench/raw/pong",
                                      [&](const Msg&) { raw.replies.fetch_add(1); });
    Pinger<LayerEndpoint> layer;
    layer.endpoint =
        std::make_unique<LayerEndpoint>(cfg, kLayerPing, kLayerPong, [&](const Msg&) { layer.replies.fetch_add(1); });
    if (!wait_matched(*raw.endpoint) || !wait_matched(*layer.endpoint))
        throw dw::RuntimeError("the echo process did not match");
    std::this_thread::sleep_for(300ms);
    raw.run(500);  // warm-up: caches, allocations, the ack machinery
    layer.run(500);

    std::vector<double> raw_all, layer_all;
    for (int r = 0; r < rounds; ++r) {
        auto a = raw.run(per_round);
        auto b = layer.run(per_round);
        raw_all.insert(raw_all.end(), a.begin(), a.end());
        layer_all.insert(layer_all.end(), b.begin(), b.end());
        std::fprintf(stderr, "\rround %d/%d", r + 1, rounds);
    }
    std::fprintf(stderr, "\n");
    ponger.stop();

    auto row = [](const char* name, const std::vector<double>& v) {
        const double mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
        std::printf("| %-15s | %7zu | %8.1f | %8.1f | %8.1f | %8.1f |\n", name, v.size(), percentile(v, 50),
                    percentile(v, 90), percentile(v, 99), mean);
    };
    std::printf("transport %s, message dw::msg::WrenchStamped, RELIABLE, round trip in µs\n\n",
                dw::dds::to_string(cfg.transport).c_str());
    std::printf("| stack           | samples |   p50    |   p90    |   p99    |   mean   |\n");
    std::printf("|-----------------|---------|----------|----------|----------|----------|\n");
    row("raw Fast DDS", raw_all);
    row("lab layer", layer_all);
    const double overhead = (percentile(layer_all, 50) / percentile(raw_all, 50) - 1.0) * 100.0;
    std::printf("\nlayer overhead at p50: %+.1f %% (target <= +10 %%)\n", overhead);
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-pingpong", [&] { return run(argc, argv); });
}
