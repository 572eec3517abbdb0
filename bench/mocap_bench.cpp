// dw-bench-mocap: the NatNet emulator at 180 Hz on loopback -> dw-mocap-bridge -> a DDS
// subscriber in this process, for a minute: frames lost, the latency the bridge adds (packet
// received by the bridge -> sample received by the subscriber) and the bridge's CPU use.
//   build/bin/dw-bench-mocap [--seconds 60]
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <thread>

#include "core/files.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/process_cli.hpp"
#include "dds/time.hpp"

namespace {
double cpu_seconds(pid_t pid) {
    std::ifstream in("/proc/" + std::to_string(pid) + "/stat");
    std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::istringstream fields(s.substr(s.rfind(')') + 2));
    std::string f;
    long utime = 0, stime = 0;
    for (int i = 3; i <= 15 && fields >> f; ++i) {
        if (i == 14) utime = std::stol(f);
        if (i == 15) stime = std::stol(f);
    }
    return static_cast<double>(utime + stime) / static_cast<double>(sysconf(_SC_CLK_TCK));
}
}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-mocap", [&] {
        dw::dds::ProcessCli cli("dw-bench-mocap: bridge loss, added latency and CPU at 180 Hz");
        double seconds = 60;
        cli.app().add_option("--seconds", seconds, "how long to stream")->check(dw::cli::in({1, 3600, "s"}));
        cli.parse(argc, argv);
        dw::dds::DdsConfig cfg = cli.dds();
        if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "benchmocap" + std::to_string(::getpid());
        const std::string port = std::to_string(20000 + ::getpid() % 20000);
        const std::string dir = dw::executable_dir();
        std::vector<std::string> dds = dw::dds::to_args(cfg);

        dw::dds::Participant p(cfg, "bench");
        std::mutex m;
        std::set<std::uint64_t> frames;
        std::vector<double> latency_us;
        dw::dds::Reader<dw::msg::MocapFrame> reader(
            p, dw::dds::topics::mocap_frame, [&](const auto& f, const dw::dds::SampleMeta& meta) {
                std::lock_guard lock(m);
                frames.insert(f.frame_number());
                latency_us.push_back(static_cast<double>(meta.reception_time_ns - dw::dds::from_msg(f.receive())) /
                                     1000.0);
            });
        dw::Subprocess emulator({{dir + "/dw-natnet-emulator", "--port", port, "--rate", "180"},
                                 "/tmp/dw-bench-mocap-emulator.log",
                                 "/tmp/dw-bench-mocap-emulator.log",
                                 {}});
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        std::vector<std::string> bridge_args{dir + "/dw-mocap-bridge", "--command-port", port};
        bridge_args.insert(bridge_args.end(), dds.begin(), dds.end());
        dw::Subprocess bridge({bridge_args, "/tmp/dw-bench-mocap-bridge.log", "/tmp/dw-bench-mocap-bridge.log", {}});
        if (!reader.wait_for_writers(1, std::chrono::seconds(30))) throw dw::RuntimeError("the bridge did not come up");
        std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
        const double cpu = cpu_seconds(bridge.pid());
        emulator.stop();
        std::this_thread::sleep_for(std::chrono::milliseconds(300));
        bridge.stop();
        const std::string log = dw::read_file("/tmp/dw-bench-mocap-emulator.log");
        const auto at = log.find("sent ");
        const long sent = at == std::string::npos ? -1 : std::stol(log.substr(at + 5));
        std::lock_guard lock(m);
        std::sort(latency_us.begin(), latency_us.end());
        auto pct = [&](double q) {
            return latency_us.empty()
                       ? 0.0
                       : latency_us[static_cast<std::size_t>(q / 100 * static_cast<double>(latency_us.size() - 1))];
        };
        const std::uint64_t span = frames.empty() ? 0 : *frames.rbegin() - *frames.begin() + 1;
        std::printf(
            "| seconds | frames sent by the emulator | received by the subscriber | missing between the first and last "
            "received | added latency p50 | p99 | max | bridge CPU |\n");
        std::printf("|---|---|---|---|---|---|---|---|\n");
        std::printf("| %.0f | %ld | %zu | %llu | %.0f µs | %.0f µs | %.0f µs | %.1f %% of a core |\n", seconds, sent,
                    frames.size(), static_cast<unsigned long long>(span - frames.size()), pct(50), pct(99),
                    latency_us.empty() ? 0.0 : latency_us.back(), 100.0 * cpu / seconds);
        std::printf("\ntargets: no frame lost by the bridge; added latency p99 < 1 ms\n");
        return 0;
    });
}
