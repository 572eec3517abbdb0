// dw-bench-physics: the downwash physics' speed, beside the anchors it is judged against.
//  - single-producer wrench evaluations per second per core at the default planform resolution,
//    beside a roofline estimate of the same computation from this machine's measured arithmetic
//    throughput (flops, divisions, square roots; the planform fits in L1, so memory is no bound);
//  - `dw-sim fly` of a 36-leg Leader Follower K=3 experiment, simulation plus writing the folder.
//
//   build/bin/dw-bench-physics --benchmark_counters_tabular=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>

#include "flight/flight.hpp"
#include "physics/flight_sim.hpp"
#include "physics/wrench_model.hpp"

using namespace dw::physics;

namespace {

// Work of one single-producer evaluation, counted from wrench_model.cpp: per planform cell the
// velocity costs ~70 flops and one division (with the wake's transport delay, computed whether
// enabled or not: the loop has no branch); the drag ~24 flops and a square root. The anchors are
// scalar: the velocity and drag loops take two cells per instruction (SSE2), or four where the
// CPU has AVX2, so the measured rate may pass this roofline.
constexpr double kFlopsPerCell = 94;
constexpr double kDivsPerCell = 1;
constexpr double kSqrtsPerCell = 1;

std::vector<Producer> random_producers(const WrenchModel& m, std::size_t n) {
    std::mt19937_64 rng(1);
    std::uniform_real_distribution<double> lateral(-1.0, 1.0), alt(0.3, 1.4);
    std::vector<Producer> out;
    for (std::size_t i = 0; i < n; ++i) out.push_back(m.producer(Vec3(lateral(rng), lateral(rng), -1.4 - alt(rng))));
    return out;
}

void BM_SingleProducerWrench(benchmark::State& state) {
    const PhysicsConfig c;
    const WrenchModel m(c);
    const Vec3 suf(0, 0, -1.4);
    const auto ps = random_producers(m, 1024);
    std::size_t i = 0;
    for (auto _ : state) {
        benchmark::DoNotOptimize(m.evaluate(suf, std::span<const Producer>(&ps[i++ & 1023], 1)));
    }
    state.counters["evals_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
    state.counters["cells"] = static_cast<double>(m.planform().size());
}
BENCHMARK(BM_SingleProducerWrench);

// Anchors: what this core does per second of each kind of arithmetic the evaluation needs, with
// the same compiler and flags; 32 independent chains, so throughput, not latency, is measured.
constexpr int kLanes = 32;
struct Lanes {
    double x[kLanes];
    Lanes() {
        for (int i = 0; i < kLanes; ++i) x[i] = 1.0 + 0.01 * i;
    }
};
void BM_AnchorFlops(benchmark::State& state) {
    Lanes a;
    const double m = 0.999999, k = 1e-7;
    for (auto _ : state) {
        for (int r = 0; r < 64; ++r) {
            for (double& x : a.x) x = x * m + k;  // 2 flops
        }
        benchmark::DoNotOptimize(a);
    }
    state.counters["flops_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * 64 * kLanes * 2, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AnchorFlops);

void BM_AnchorDivisions(benchmark::State& state) {
    Lanes a;
    for (auto _ : state) {
        for (int r = 0; r < 64; ++r) {
            for (double& x : a.x) x = 1.0 / (x + 1e-9);
        }
        benchmark::DoNotOptimize(a);
    }
    state.counters["divs_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * 64 * kLanes, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AnchorDivisions);

void BM_AnchorSqrt(benchmark::State& state) {
    Lanes a;
    for (auto _ : state) {
        for (int r = 0; r < 64; ++r) {
            for (double& x : a.x) x = std::sqrt(x + 0.5);
        }
        benchmark::DoNotOptimize(a);
    }
    state.counters["sqrts_per_s"] =
        benchmark::Counter(static_cast<double>(state.iterations()) * 64 * kLanes, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_AnchorSqrt);

void BM_SimFly36LegsLeaderFollower3(benchmark::State& state) {
    const PhysicsConfig c;
    FlyOptions o;
    o.formation = "leader_follower3";
    o.grid.legs = 36;
    const std::string dir = (std::filesystem::temp_directory_path() / "dw-bench-fly").string();
    double flight_s = 0;
    for (auto _ : state) {
        const auto r = simulate_flight(c, o);
        dw::flight::write_flight(r.flight, dir);
        flight_s = r.truth_t.back();
    }
    std::filesystem::remove_all(dir);
    state.counters["flight_s"] = flight_s;
}
BENCHMARK(BM_SimFly36LegsLeaderFollower3)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace

// Keeps every counter of the run, to put the measurement beside its roofline at the end.
class Capture : public benchmark::ConsoleReporter {
public:
    std::map<std::string, double> counters;
    void ReportRuns(const std::vector<Run>& runs) override {
        for (const auto& r : runs) {
            for (const auto& [name, c] : r.counters) counters[name] = c.value;
        }
        ConsoleReporter::ReportRuns(runs);
    }
};

int main(int argc, char** argv) {
    benchmark::Initialize(&argc, argv);
    if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 2;
    Capture capture;
    benchmark::RunSpecifiedBenchmarks(&capture);
    benchmark::Shutdown();
    auto& c = capture.counters;
    if (!c.count("evals_per_s") || !c.count("flops_per_s") || !c.count("divs_per_s") || !c.count("sqrts_per_s"))
        return 0;
    const double cells = c["cells"];
    const double flops = cells * kFlopsPerCell, divs = cells * kDivsPerCell, roots = cells * kSqrtsPerCell;
    const double roofline = 1.0 / (flops / c["flops_per_s"] + divs / c["divs_per_s"] + roots / c["sqrts_per_s"]);
    std::printf("\nsingle-producer wrench, %g cells: %.0f flops + %.0f divisions + %.0f square roots per evaluation\n",
                cells, flops, divs, roots);
    std::printf(
        "measured %.3g evaluations/s per core; roofline estimate %.3g/s (compute-bound, planform in L1); "
        "%.0f %% of the scalar roofline; target >= 1e6/s\n",
        c["evals_per_s"], roofline, 100.0 * c["evals_per_s"] / roofline);
    return 0;
}
