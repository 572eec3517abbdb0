// dw-bench-predictor: (1) online inference for K = 3 per prediction (Deep Sets, learnt linear;
// the physics model beside them); (2) a contour map's rendering; (3) training on 100 000
// samples to convergence (Deep Sets, learnt linear beside it); (4) mocap frame -> prediction
// sample end to end over loopback DDS, dw-predictor run in its own process.
//   build/bin/dw-bench-predictor [--parts inference,map,train,e2e] [--frames 3600]
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <random>
#include <thread>

#include "core/log.hpp"
#include "core/subprocess.hpp"
#include "dds/endpoint.hpp"
#include "dds/process_cli.hpp"
#include "dds/time.hpp"
#include "flight/flight.hpp"
#include "physics/flight_sim.hpp"
#include "predictor/maps.hpp"
#include "predictor/model.hpp"
#include "predictor/train.hpp"
#include "testkit/mlp.hpp"
#include "testkit/mocap.hpp"

using namespace dw::predictor;
using Clock = std::chrono::steady_clock;

namespace {

double percentile(std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

// An untrained model of the study's sizes: inference time does not depend on the weights. Deep
// Sets carries a learnt linear baseline, as the study's does.
LearntModel sized_model(Structure s, unsigned seed = 1) {
    std::mt19937 rng(seed);
    auto mlp = [&](const std::vector<int>& sizes) { return dw::testkit::random_mlp(rng, sizes, 0.3f); };
    LearntModel m;
    m.kind = s == Structure::sum ? "learnt_linear" : "deep_sets";
    m.structure = s;
    m.input_std.fill(1);
    m.output_scale.fill(1);
    m.phi = mlp({kFeatureSize, 64, 64, s == Structure::sum ? 6 : 32});
    if (s == Structure::deep_sets) {
        m.rho = mlp({32, 64, 64, 6});
        m.baseline = mlp({kFeatureSize, 64, 64, 6});
    }
    return m;
}

// Deep Sets as the study serves it: the average of kDefaultDeepSetsMembers trainings (average_of).
LearntModel served_deep_sets() {
    std::vector<LearntModel> members;
    for (int i = 0; i < kDefaultDeepSetsMembers; ++i)
        members.push_back(sized_model(Structure::deep_sets, static_cast<unsigned>(i + 1)));
    LearntModel m = average_of(members);
    m.kind = dw::log::cat("deep_sets (", kDefaultDeepSetsMembers, " trainings averaged, as served)");
    return m;
}

void inference() {
    const LearntModel deep = sized_model(Structure::deep_sets), lin = sized_model(Structure::sum);
    const LearntModel served = served_deep_sets();
    const PhysicsModel phys(dw::physics::PhysicsConfig{});
    std::printf("| model (K = 3, one prediction) | p50 µs | p99 µs | target p99 |\n|---|---|---|---|\n");
    for (const ForceModel* m : std::initializer_list<const ForceModel*>{&deep, &served, &lin, &phys}) {
        std::vector<double> us;
        double sink = 0;
        for (int i = 0; i < 20000; ++i) {
            const double e = -1.0 + 2.0 * (i % 1000) / 1000.0;
            const std::vector<RelState> x{
                {0, e + 0.5, -1.3, 0, 0.5, 0}, {0, e, -1.3, 0, 0.5, 0}, {0, e - 0.5, -1.3, 0, 0.5, 0}};
            const auto t0 = Clock::now();
            sink += m->predict(x)[2];
            us.push_back(std::chrono::duration<double, std::micro>(Clock::now() - t0).count());
        }
        std::printf("| %s | %.1f | %.1f | %s |\n", m->name().c_str(), percentile(us, 0.5), percentile(us, 0.99),
                    m == &phys ? "(anchor: the simulator)" : "<= 100");
        if (sink == 12345.678) std::printf(" ");
    }
    std::printf("\n");
}

void map() {
    const LearntModel deep = sized_model(Structure::deep_sets), lin = sized_model(Structure::sum), naive = lin;
    const PhysicsModel phys(dw::physics::PhysicsConfig{});
    const auto dir = std::filesystem::temp_directory_path();
    std::printf("| contour map (61 x 61 grid, leader_follower3) | seconds (median of 5) | target |\n|---|---|---|\n");
    for (int panels : {1, 4}) {
        std::vector<const ForceModel*> models{&phys, &naive, &lin, &deep};
        models.resize(static_cast<std::size_t>(panels));
        std::vector<double> s;
        for (int i = 0; i < 5; ++i) {
            MapRequest r;
            const auto t0 = Clock::now();
            draw_force_map(models, r, (dir / "dw-bench-map.png").string());
            s.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
        }
        std::printf("| %d panel%s (physics%s) | %.3f | %s |\n", panels, panels > 1 ? "s" : "",
                    panels > 1 ? " + three learnt models" : " only: anchor", percentile(s, 0.5),
                    panels > 1 ? "<= 0.5" : "");
    }
    std::filesystem::remove(dir / "dw-bench-map.png");
    std::printf("\n");
}

void train() {
    // Simulated flights of every formation until 100 000 training samples on legs.
    Dataset all;
    std::uint64_t seed = 100;
    const auto tmp = std::filesystem::temp_directory_path() / ("dw-bench-train-" + std::to_string(::getpid()));
    for (const char* f : {"single", "side_by_side", "leader_follower", "leader_follower3", "stack", "hybrid", "single",
                          "leader_follower3", "stack", "hybrid"}) {
        dw::physics::FlyOptions fly;
        fly.formation = f;
        fly.grid.legs = 60;
        fly.seed = seed++;
        dw::flight::write_flight(dw::physics::simulate_flight(dw::physics::PhysicsConfig{}, fly).flight, tmp.string());
        all.append(load_dataset(tmp.string()));
    }
    std::filesystem::remove_all(tmp);
    Split sp = split_by_leg(all);
    if (sp.train.samples.size() > 100000) sp.train.samples.resize(100000);
    std::printf(
        "| training (%zu samples, %zu validation, %d thread%s) | epochs (best) | seconds | target "
        "|\n|---|---|---|---|\n",
        sp.train.samples.size(), sp.validation.samples.size(), kDefaultTrainThreads,
        kDefaultTrainThreads == 1 ? "" : "s");
    for (const char* kind : {"deep_sets", "learnt_linear"}) {
        TrainOptions o;
        o.kind = kind;
        const auto r = train_model(sp.train, sp.validation, o);
        std::printf("| %s | %d (%d) | %.1f | %s |\n", kind, r.epochs, r.best_epoch, r.seconds,
                    std::string(kind) == "deep_sets" ? "<= 120" : "(anchor)");
    }
    std::printf("\n");
}

void e2e(const dw::dds::DdsConfig& cfg, int frames) {
    const auto model =
        std::filesystem::temp_directory_path() / ("dw-bench-model-" + std::to_string(::getpid()) + ".json");
    sized_model(Structure::deep_sets).save(model.string());
    dw::Subprocess node({{dw::executable_dir() + "/dw-predictor", "run", "--model", model.string(), "--domain",
                          std::to_string(cfg.domain), "--namespace", cfg.ns},
                         "/dev/null",
                         "/dev/null",
                         {}});
    dw::dds::Participant p(cfg, "bench");
    dw::SystemClock clock;
    std::mutex m;
    std::vector<double> us, age_us;
    dw::dds::Reader<dw::msg::WrenchPrediction> reader(
        p, dw::dds::topics::wrench_prediction, [&](const auto& s, const auto&) {
            const double lat = static_cast<double>(clock.now_ns() - dw::dds::from_msg(s.header().stamp())) * 1e-3;
            std::lock_guard lock(m);
            us.push_back(lat);
            age_us.push_back(s.input_age_s() * 1e6);
        });
    dw::dds::Writer<dw::msg::MocapFrame> writer(p, dw::dds::topics::mocap_frame);
    if (!writer.wait_for_readers(1, std::chrono::seconds(20))) throw dw::RuntimeError("dw-predictor run did not start");
    reader.wait_for_writers(1, std::chrono::seconds(20));
    for (int i = 0; i < frames; ++i) {
        dw::msg::MocapFrame f;
        f.frame_number(static_cast<std::uint64_t>(i));
        const double e = -1.0 + 2.0 * (i % 720) / 720.0;
        dw::testkit::add_body(f, "sufferer", 0, 0, -1.4);
        for (int j = 0; j < 3; ++j) dw::testkit::add_body(f, "v" + std::to_string(j + 1), 0, e + 0.5 * (j - 1), -2.7);
        f.header().stamp(dw::dds::to_msg(clock.now_ns()));
        writer.write(f);
        std::this_thread::sleep_for(std::chrono::microseconds(5556));  // 180 Hz
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(300));
    node.stop();
    std::filesystem::remove(model);
    std::lock_guard lock(m);
    std::printf(
        "| mocap frame -> prediction (K = 3, Deep Sets, loopback, 180 Hz) | frames | received | p50 µs | p99 µs | "
        "target p99 |\n"
        "|---|---|---|---|---|---|\n");
    std::printf("| end to end (frame stamped at write -> sample received) | %d | %zu | %.0f | %.0f | <= 1000 |\n",
                frames, us.size(), percentile(us, 0.5), percentile(us, 0.99));
    std::printf(
        "| of which to the prediction's write (input_age_s: DDS to the node + features + inference) | | | %.0f | %.0f "
        "| |\n\n",
        percentile(age_us, 0.5), percentile(age_us, 0.99));
}

}  // namespace

int main(int argc, char** argv) {
    return dw::cli::run_main("dw-bench-predictor", [&] {
        dw::dds::ProcessCli cli(
            "dw-bench-predictor: inference, map rendering, training and end-to-end latency of the predictor");
        std::string parts = "inference,map,train,e2e";
        int frames = 3600;
        cli.app().add_option("--parts", parts, "which parts, comma-separated");
        cli.app().add_option("--frames", frames, "end to end: frames at 180 Hz")->check(dw::cli::in({1, 1e7}));
        cli.parse(argc, argv);
        dw::dds::DdsConfig cfg = cli.dds();
        if (cfg.ns == dw::dds::kDefaultNamespace) cfg.ns = "benchpred" + std::to_string(::getpid());
        if (parts.find("inference") != std::string::npos) inference();
        if (parts.find("map") != std::string::npos) map();
        if (parts.find("train") != std::string::npos) train();
        if (parts.find("e2e") != std::string::npos) e2e(cfg, frames);
        return 0;
    });
}
