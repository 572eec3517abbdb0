// dw-bench-mcap: the MCAP writer's in-process throughput per compression, beside `dd` writing to
// the same disk in the same run (the physical limit).
//   build/bin/dw-bench-mcap [--dir DIR] [--benchmark_counters_tabular=true]
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <random>
#include <string>

#include "mcap/mcap.hpp"

namespace {

std::string g_dir = "/tmp";

std::vector<std::uint8_t> message(std::size_t size, std::uint64_t seed) {
    // Wrench-like: mostly doubles that change a little; compressible but not trivially.
    std::vector<std::uint8_t> d(size);
    std::mt19937_64 rng(seed);
    for (std::size_t i = 0; i < size; ++i) d[i] = static_cast<std::uint8_t>(i % 8 < 5 ? i : rng());
    return d;
}

void run_writer(benchmark::State& state, dw::mcap::Compression c, std::size_t size, bool fsync) {
    const std::string path = g_dir + "/dw-bench.mcap";
    const std::size_t n = size < 4096 ? 1'000'000 : 2000;  // ~100 MB or ~2 GB per iteration
    const auto msg = message(size, 1);
    std::uint64_t bytes = 0;
    for (auto _ : state) {
        dw::mcap::WriterOptions o;
        o.compression = c;
        o.fsync = fsync;
        dw::mcap::Writer w(path, o);
        const auto s = w.add_schema("dw::msg::WrenchStamped", "omgidl", "");
        const auto ch = w.add_channel("rt/lab/stand/wrench", s, "cdr", {});
        for (std::size_t i = 0; i < n; ++i) {
            w.write({ch, static_cast<std::uint32_t>(i), i * 1000, i * 1000, msg}, 0);
        }
        w.close();
        bytes = w.bytes_written();
    }
    std::filesystem::remove(path);
    state.counters["msgs_per_s"] =
        benchmark::Counter(static_cast<double>(n * state.iterations()), benchmark::Counter::kIsRate);
    state.counters["MB_per_s_in"] =
        benchmark::Counter(static_cast<double>(n * size * state.iterations()) / 1e6, benchmark::Counter::kIsRate);
    state.counters["file_MB"] = static_cast<double>(bytes) / 1e6;
}

void BM_Small_None(benchmark::State& s) { run_writer(s, dw::mcap::Compression::none, 85, false); }
void BM_Small_Zstd(benchmark::State& s) { run_writer(s, dw::mcap::Compression::zstd, 85, false); }
void BM_Small_Lz4(benchmark::State& s) { run_writer(s, dw::mcap::Compression::lz4, 85, false); }
void BM_Small_Zstd_Fsync(benchmark::State& s) { run_writer(s, dw::mcap::Compression::zstd, 85, true); }
void BM_Large_None_Fsync(benchmark::State& s) { run_writer(s, dw::mcap::Compression::none, 1 << 20, true); }
void BM_Large_Lz4_Fsync(benchmark::State& s) { run_writer(s, dw::mcap::Compression::lz4, 1 << 20, true); }
BENCHMARK(BM_Small_None)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(BM_Small_Zstd)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(BM_Small_Lz4)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(BM_Small_Zstd_Fsync)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();
BENCHMARK(BM_Large_None_Fsync)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();
BENCHMARK(BM_Large_Lz4_Fsync)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();

// The anchor: dd writing 2 GB sequentially to the same directory, synced, as the disk's limit.
void BM_Anchor_dd(benchmark::State& state) {
    const std::string path = g_dir + "/dw-bench-dd";
    for (auto _ : state) {
        const std::string cmd = "dd if=/dev/zero of=" + path + " bs=1M count=2000 conv=fdatasync status=none";
        if (std::system(cmd.c_str()) != 0) state.SkipWithError("dd failed");
    }
    std::filesystem::remove(path);
    state.counters["MB_per_s_in"] = benchmark::Counter(2000.0 * 1048576 / 1e6 * static_cast<double>(state.iterations()),
                                                       benchmark::Counter::kIsRate);
}
BENCHMARK(BM_Anchor_dd)->Unit(benchmark::kMillisecond)->Iterations(2)->UseRealTime();

}  // namespace

int main(int argc, char** argv) {
    for (int i = 1; i + 1 < argc; ++i) {
        if (std::string(argv[i]) == "--dir") {
            g_dir = argv[i + 1];
            for (int k = i; k + 2 <= argc; ++k) argv[k] = argv[k + 2];
            argc -= 2;
            break;
        }
    }
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
    return 0;
}
