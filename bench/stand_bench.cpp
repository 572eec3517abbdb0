// dw-bench-stand: (1) line operations per 8-cell sample, parallel read on a shared clock beside
// reading the cells one by one; (2) sample-to-publish latency (ADC conversion excluded): from the
// end of the bit-banged read to the wrench handed to DDS, with a subscriber in another process.
//   build/bin/dw-bench-stand [--samples 5000]
#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "core/subprocess.hpp"
#include "dds/process_cli.hpp"
#include "stand_agent/agent.hpp"
#include "stand_agent/emulated_bank.hpp"
#include "stand_agent/hx711.hpp"
#include "dds/endpoint.hpp"

using namespace dw::stand;

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-stand", [&] {
        dw::dds::ProcessCli cli("dw-bench-stand: HX711 line operations and sample-to-publish latency");
        int samples = 5000;
        cli.app().add_option("--samples", samples, "latency samples")->check(dw::cli::in({1, 1e7}));
        cli.parse(argc, argv);
        dw::dds::DdsConfig cfg = cli.dds();
        if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "benchstand" + std::to_string(::getpid());

        // (1) line operations, in virtual time
        auto ops = [](bool shared) {
            dw::ManualClock clock;
            BankOptions b;
            b.shared_clock = shared;
            EmulatedBank bank(clock, b, [](int, dw::Nanos) { return 1.0; });
            Hx711Driver d(bank, {});
            std::uint64_t total = 0;
            for (int i = 0; i < 100; ++i) {
                clock.advance(std::chrono::milliseconds(20));  // conversions waiting: no polling
                total += (shared ? d.read_parallel() : d.read_one_by_one()).ops;
            }
            return static_cast<double>(total) / 100.0;
        };
        std::printf("| read | line operations per 8-cell sample |\n|---|---|\n");
        std::printf("| parallel (shared clock, bulk DOUT read) | %.0f (target <= 80) |\n", ops(true));
        std::printf("| one by one (a clock per chip) | %.0f |\n\n", ops(false));

        // (2) latency, in real time: a fast emulated bank (1 kHz) so thousands of samples take seconds
        dw::Subprocess echo({{dw::executable_dir() + "/dw-probe", "echo", "stand/wrench", "--quiet", "--domain",
                              std::to_string(cfg.domain), "--namespace", cfg.ns},
                             "/dev/null",
                             "/dev/null",
                             {}});
        dw::dds::Participant p(cfg, "stand_agent");
        dw::dds::Writer<dw::msg::LoadCellFrame> frames(p, dw::dds::topics::stand_cells);
        dw::dds::Writer<dw::msg::WrenchStamped> wrench(p, dw::dds::topics::stand_wrench);
        if (!wrench.wait_for_readers(1, std::chrono::seconds(30)))
            throw dw::RuntimeError("the subscriber did not match");
        BankOptions b;
        b.rate_hz = 1000;
        b.noise_counts = 500;
        EmulatedBank bank(dw::SystemClock::instance(), b, [](int, dw::Nanos) { return 0.5; });
        Hx711Driver driver(bank, {});
        AgentOptions a;
        a.calibration = Calibration::nominal(dw::physics::StandParams{});
        StandAgent agent(a, dw::SystemClock::instance());
        std::vector<double> us;
        while (static_cast<int>(us.size()) < samples) {
            const Hx711Sample s = driver.read_parallel();
            auto out = agent.process(s);
            if (!out.publish) continue;
            frames.write(out.frame);
            wrench.write(out.wrench);
            us.push_back(static_cast<double>(dw::SystemClock::instance().monotonic_ns() - s.finished_ns) / 1000.0);
        }
        echo.stop();
        std::sort(us.begin(), us.end());
        auto pct = [&](double q) {
            return us[static_cast<std::size_t>(q / 100.0 * static_cast<double>(us.size() - 1))];
        };
        std::printf(
            "| sample -> publish (frame + wrench written) | samples | p50 | p99 | max |\n|---|---|---|---|---|\n");
        std::printf("| µs | %zu | %.1f | %.1f | %.1f |\n", us.size(), pct(50), pct(99), us.back());
        std::printf("\ntarget: p99 < 200 µs\n");
        return 0;
    });
}
