// dw-bench-viewer: DDS sample -> WebSocket frame latency through dw-viewer (issue 72), beside its
// anchor, the DDS hop to another process, in one run. A writer publishes the stand's wrench at
// 80 Hz and the mocap frame at 180 Hz (the lab's rates), each wrench stamped with the time it is
// written; a reader in a child process (this program, --anchor) measures the hop; 1, then 4,
// Foxglove clients (Beast, in this process) subscribed to every channel of a dw-viewer process
// measure the same stamps on arrival.
// The viewer's CPU over each run from /proc.
//   dw-bench-viewer [--seconds 20]
#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <cstring>
#include <cmath>
#include <nlohmann/json.hpp>
#include <thread>

#include "core/files.hpp"
#include "core/shutdown.hpp"
#include <iostream>
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/process_cli.hpp"
#include "dds/time.hpp"

namespace beast = boost::beast;
namespace websocket = beast::websocket;
using tcp = boost::asio::ip::tcp;
using namespace std::chrono_literals;

namespace {

constexpr double kWrenchHz = 80, kMocapHz = 180;
constexpr std::size_t kStampOffset = 4 + 1 + 4 + 8;  // after the encapsulation and MessageData's header

double percentile(std::vector<double> v, double p) {
    if (v.empty()) return NAN;
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(p / 100.0 * static_cast<double>(v.size() - 1))];
}

double now_ns() { return static_cast<double>(dw::SystemClock::instance().now_ns()); }

// One Foxglove client: subscribes to every channel, records each wrench's age on arrival [ms].
struct WsClient {
    std::vector<double> ms;
    std::atomic<bool> stop{false};
    std::thread thread;
    void run(const std::string& port, const std::string& wrench_topic) {
        boost::asio::io_context io;
        websocket::stream<tcp::socket> ws(io);
        boost::asio::connect(ws.next_layer(), tcp::resolver(io).resolve("127.0.0.1", port));
        ws.set_option(websocket::stream_base::decorator([](websocket::request_type& r) {
            r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
        }));
        ws.handshake("127.0.0.1", "/");
        beast::flat_buffer buf;
        std::uint32_t wrench_sub = ~0u;
        while (!stop) {
            ws.read(buf);
            const auto data = static_cast<const std::uint8_t*>(buf.data().data());
            if (!ws.got_text() && buf.size() > kStampOffset + 8 && data[0] == 1) {
                std::uint32_t sub = 0;
                std::memcpy(&sub, data + 1, 4);
                std::int32_t sec = 0;
                std::uint32_t nsec = 0;
                std::memcpy(&sec, data + kStampOffset, 4);
                std::memcpy(&nsec, data + kStampOffset + 4, 4);
                if (sub == wrench_sub) ms.push_back((now_ns() - (sec * 1e9 + nsec)) / 1e6);
            } else if (ws.got_text()) {
                const auto j = nlohmann::json::parse(beast::buffers_to_string(buf.data()), nullptr, false);
                if (j.is_object() && j.value("op", "") == "advertise") {
                    nlohmann::json subs = nlohmann::json::array();
                    for (const auto& c : j["channels"]) {
                        subs.push_back({{"id", c["id"]}, {"channelId", c["id"]}});
                        if (c["topic"] == wrench_topic) wrench_sub = c["id"].get<std::uint32_t>();
                    }
                    ws.write(boost::asio::buffer(nlohmann::json{{"op", "subscribe"}, {"subscriptions", subs}}.dump()));
                }
            }
            buf.consume(buf.size());
        }
        beast::error_code ec;
        ws.next_layer().close(ec);
    }
};

double cpu_seconds(pid_t pid) {
    std::ifstream f("/proc/" + std::to_string(pid) + "/stat");
    std::string s((std::istreambuf_iterator<char>(f)), {});
    const auto close = s.rfind(')');
    std::istringstream in(s.substr(close + 2));
    std::string field;
    double utime = 0, stime = 0;
    for (int i = 3; i <= 15 && in >> field; ++i) {
        if (i == 14) utime = std::stod(field);
        if (i == 15) stime = std::stod(field);
    }
    return (utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
}

// --anchor: the DDS hop, each wrench's age on arrival in this process [ms]; "p50 p99 n" on SIGINT.
int run_anchor(const dw::dds::DdsConfig& cfg) {
    dw::dds::Participant p(cfg, "bench-anchor");
    std::mutex m;
    std::vector<double> hop;
    dw::dds::Reader<dw::msg::WrenchStamped> reader(
        p, dw::dds::topics::stand_wrench, [&](const dw::msg::WrenchStamped& w, const dw::dds::SampleMeta&) {
            std::lock_guard l(m);
            hop.push_back((now_ns() - dw::dds::from_msg(w.header().stamp())) / 1e6);
        });
    std::cout << "anchor ready" << std::endl;
    while (!dw::Shutdown::instance().wait_for(100ms)) {}
    std::lock_guard l(m);
    std::cout << percentile(hop, 50) << " " << percentile(hop, 99) << " " << hop.size() << std::endl;
    return 0;
}

}  // namespace

int run(int argc, char** argv) {
    dw::dds::ProcessCli cli("dw-bench-viewer: DDS sample to WebSocket frame latency through dw-viewer");
    double seconds = 20;
    cli.app().add_option("--seconds", seconds, "per run (1 client, then 4)")->check(dw::cli::in({2, 3600, "s"}));
    bool anchor_mode = false;
    cli.app().add_flag("--anchor", anchor_mode, "(internal) the DDS hop's reader");
    cli.parse(argc, argv);
    auto cfg = cli.dds();
    if (anchor_mode) return run_anchor(cfg);
    if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "bench" + std::to_string(::getpid());
    std::vector<std::string> args{dw::executable_dir() + "/dw-viewer", "--port", "0"};
    for (const auto& a : dw::dds::to_args(cfg)) args.push_back(a);
    const std::string out = "/tmp/dw-bench-viewer-" + std::to_string(::getpid()) + ".out", err = out + ".err";
    dw::Subprocess viewer({args, out, err, {}});
    std::string port;
    for (int i = 0; i < 1000 && port.empty(); ++i, std::this_thread::sleep_for(10ms)) {
        const auto text = std::filesystem::exists(out) ? dw::read_file(out) : std::string();
        const auto nl = text.find("/\n");
        if (nl != std::string::npos) port = text.substr(text.rfind(':', nl) + 1, nl - text.rfind(':', nl) - 1);
    }
    if (port.empty()) throw dw::RuntimeError("dw-viewer did not start: " + dw::read_file(err));

    dw::dds::Participant lab(cfg, "bench-lab");
    dw::dds::Writer<dw::msg::WrenchStamped> wrench(lab, dw::dds::topics::stand_wrench);
    dw::dds::Writer<dw::msg::MocapFrame> mocap(lab, dw::dds::topics::mocap_frame);
    std::printf(
        "| clients | DDS hop p50 / p99 [ms] | WebSocket frame p50 / p99 [ms] | frames | viewer CPU [%% of a core] "
        "|\n|---|---|---|---|---|\n");
    for (int clients : {1, 4}) {
        std::vector<std::unique_ptr<WsClient>> ws;
        for (int k = 0; k < clients; ++k) {
            ws.push_back(std::make_unique<WsClient>());
            auto* c = ws.back().get();
            c->thread =
                std::thread([c, &port, &lab] { c->run(port, lab.topic_name(dw::dds::topics::stand_wrench.suffix)); });
        }
        std::vector<std::string> anchor_args{dw::executable_dir() + "/dw-bench-viewer", "--anchor"};
        for (const auto& a : dw::dds::to_args(cfg)) anchor_args.push_back(a);
        const std::string anchor_out = out + ".anchor";
        dw::Subprocess anchor({anchor_args, anchor_out, err + ".anchor", {}});
        for (int i = 0; i < 1000 && dw::read_file(anchor_out).find("ready") == std::string::npos; ++i)
            std::this_thread::sleep_for(10ms);
        std::this_thread::sleep_for(1s);
        for (auto& c : ws) c->ms.clear();
        const double cpu0 = cpu_seconds(viewer.pid());
        const auto t0 = std::chrono::steady_clock::now();
        std::uint64_t seq = 0;
        for (auto next = t0; next - t0 < std::chrono::duration<double>(seconds);
             next += std::chrono::microseconds(static_cast<long>(1e6 / kMocapHz))) {
            std::this_thread::sleep_until(next);
            dw::msg::MocapFrame f;
            f.header().stamp(dw::dds::to_msg(dw::SystemClock::instance().now_ns()));
            f.header().seq(seq);
            mocap.write(f);
            if (seq++ % 9 < 4) {  // 4 of every 9 frames: 80 Hz beside 180
                dw::msg::WrenchStamped w;
                w.header().seq(seq);
                w.header().stamp(dw::dds::to_msg(dw::SystemClock::instance().now_ns()));
                wrench.write(w);
            }
        }
        std::this_thread::sleep_for(300ms);
        const double cpu = (cpu_seconds(viewer.pid()) - cpu0) / seconds * 100;
        std::vector<std::vector<double>> got;
        for (auto& c : ws) c->stop = true;
        dw::msg::MocapFrame last;
        for (int k = 0; k < 20; ++k, std::this_thread::sleep_for(10ms)) mocap.write(last);  // unblock the reads
        for (auto& c : ws) c->thread.join();
        std::vector<double> all;
        for (auto& c : ws) all.insert(all.end(), c->ms.begin(), c->ms.end());
        anchor.stop();
        std::istringstream hop(dw::read_file(anchor_out).substr(dw::read_file(anchor_out).find('\n') + 1));
        double hop50 = NAN, hop99 = NAN;
        hop >> hop50 >> hop99;
        std::printf("| %d | %.2f / %.2f | %.2f / %.2f | %zu | %.1f |\n", clients, hop50, hop99, percentile(all, 50),
                    percentile(all, 99), all.size(), cpu);
    }
    viewer.stop();
    return 0;
}

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-viewer", [&] { return run(argc, argv); });
}
