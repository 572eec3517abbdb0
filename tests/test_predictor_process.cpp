// dw-predictor run as a process: mocap frames in, predictions out at the same rate, the model's
// value for the frame's geometry, the input's age, and a model swapped without a restart.
#include <gtest/gtest.h>

#include <functional>
#include <signal.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <thread>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/stats.hpp"
#include "dds/endpoint.hpp"
#include "dds/time.hpp"
#include "flight/flight.hpp"
#include "predictor/model.hpp"
#include "predictor/node.hpp"
#include "collected.hpp"
#include "support.hpp"
#include "testkit/mocap.hpp"

using namespace std::chrono_literals;
using namespace dw::predictor;

namespace {

LearntModel linear_model(const std::string& kind, float gain) {
    // psi(x) = gain * (dn, de, dd, 0, 0, 0) (the first features are the relative position): the sum is gain x the neighbours' summed offsets.
    LearntModel m;
    m.kind = kind;
    m.structure = Structure::sum;
    m.input_mean.fill(0);
    m.input_std.fill(1);
    m.output_scale = {1, 1, 1, 1, 1, 1};
    Layer l;
    l.silu = false;
    l.w = Eigen::MatrixXf::Zero(6, kFeatureSize);
    for (int i = 0; i < 3; ++i) l.w(i, i) = gain;
    l.b = Eigen::VectorXf::Zero(6);
    m.phi.layers.push_back(l);
    return m;
}

// f_d = the sum of the neighbours' masses [kg] (an unknown one: 0, its training mean here).
LearntModel mass_model() {
    LearntModel m = linear_model("naive_linear", 0.0f);
    m.phi.layers[0].w(2, kNeighbourMassFeature) = 1.0f;
    return m;
}

// A lab's bodies as a flight's meta.json gives them: v1 the large vehicle (or v1_params), v2 the
// small one; the sufferer on a stand (stand: true) or flying.
std::string lab_meta(dw::test::TempDir& dir, bool stand, const std::string& name = "meta.json",
                     const std::string& v1_params = R"({"mass_kg": 0.067, "rotors": 4, "prop_radius_m": 0.033,
                                                         "motor_distance_m": 0.12})") {
    const auto path = dir.file(name);
    std::ofstream(path)
        << R"({"format": "downwash-flight/1", "sufferer": "suff", "neighbours": ["v1", "v2"], "formation": "free",
        "vehicles": {"suff": {"mass_kg": 0.032, "rotors": 4, "prop_radius_m": 0.0225, "motor_distance_m": 0.092},
                     "v1": )"
        << v1_params
        << R"(, "v2": {"mass_kg": 0.032, "rotors": 4, "prop_radius_m": 0.0225, "motor_distance_m": 0.092}})"
        << (stand ? R"(, "stand": {"height_m": 1.4}})" : "}");
    return path;
}

OnlineBodies bodies_of_meta(const std::string& path) { return OnlineBodies(dw::flight::read_meta(path), path); }

// v1 and v2 of lab_meta above the sufferer "suff", and v3, which meta.json does not describe.
dw::msg::MocapFrame lab_frame(std::uint64_t n, double t_s) {
    dw::msg::MocapFrame f;
    f.header().stamp(dw::dds::to_msg(static_cast<dw::Nanos>(t_s * 1e9)));
    f.frame_number(n);
    dw::testkit::add_body(f, "suff", 0, 0, -1.0);
    dw::testkit::add_body(f, "v1", 0.05, 0, -1.5);
    dw::testkit::add_body(f, "v2", 0, 0.3, -1.6);
    dw::testkit::add_body(f, "v3", -0.4, 0, -1.7);
    return f;
}

dw::msg::MocapFrame frame(std::uint64_t n, double t_s, double e_offset) {
    dw::msg::MocapFrame f;
    f.header().stamp(dw::dds::to_msg(static_cast<dw::Nanos>(t_s * 1e9)));
    f.frame_number(n);
    dw::testkit::add_body(f, "sufferer", 0, 0, -1.4);
    dw::testkit::add_body(f, "v1", 0.2, e_offset, -2.7);
    dw::testkit::add_body(f, "v2", -0.1, e_offset + 0.5, -2.7);
    return f;
}

// A loopback configuration of the test's own namespace.
dw::dds::DdsConfig node_config(const std::string& ns) {
    dw::dds::DdsConfig cfg;
    cfg.domain = dw::test::test_domain();
    cfg.ns = ns + std::to_string(::getpid());
    return cfg;
}

// `dw-predictor run` on the model file, in cfg's namespace; output in dir/node.out and node.err.
dw::Subprocess start_node(dw::test::TempDir& dir, const std::string& model, const dw::dds::DdsConfig& cfg,
                          std::vector<std::string> extra = {}) {
    std::vector<std::string> args{dw::test::bin("dw-predictor"), "run",         "--model", model, "--domain",
                                  std::to_string(cfg.domain),    "--namespace", cfg.ns};
    args.insert(args.end(), extra.begin(), extra.end());
    return dw::Subprocess({args, dir.file("node.out"), dir.file("node.err"), {}});
}

}  // namespace

TEST(PredictorProcess, PredictsAtTheMocapRateAndSwapsModelsWithoutRestart) {
    dw::test::TempDir dir;
    const auto model = dir.file("model.json");
    linear_model("learnt_linear", 1.0f).save(model);
    const auto cfg = node_config("pred");
    dw::Subprocess node = start_node(dir, model, cfg);
    dw::dds::Participant p(cfg, "test");
    dw::test::Collected<dw::msg::WrenchPrediction> predictions(p, dw::dds::topics::wrench_prediction);
    dw::dds::Writer<dw::msg::MocapFrame> writer(p, dw::dds::topics::mocap_frame);
    ASSERT_TRUE(writer.wait_for_readers(1, 20000ms)) << dw::read_file(dir.file("node.err"));
    ASSERT_TRUE(predictions.reader().wait_for_writers(1, 20000ms));
    auto send = [&](int from, int count) {
        for (int i = from; i < from + count; ++i) {
            auto f = frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, -1.0 + 0.5 * i / 180.0);
            writer.write(f);
            std::this_thread::sleep_for(std::chrono::microseconds(5556));
        }
    };
    send(0, 180);
    std::this_thread::sleep_for(300ms);
    {
        const auto got = predictions.samples();
        EXPECT_GE(got.size(), 175u);  // best effort on loopback: one per frame
        ASSERT_FALSE(got.empty());
        const auto& last = got.back();
        EXPECT_EQ(last.model_name(), "learnt_linear");
        const double t = dw::dds::from_msg(last.header().stamp()) * 1e-9;
        const int i = static_cast<int>(std::lround((t - 1000.0) * 180.0));
        const double e = -1.0 + 0.5 * i / 180.0;
        EXPECT_NEAR(last.force_n().x(), 0.2 - 0.1, 1e-5);         // Σ dn
        EXPECT_NEAR(last.force_n().y(), e + e + 0.5, 1e-4);       // Σ de
        EXPECT_NEAR(last.force_n().z(), 2 * (-2.7 + 1.4), 1e-5);  // Σ dd
        // The age is publish time - frame stamp; the frames were stamped in 1970 + 1000 s.
        EXPECT_GT(last.input_age_s(), 1e9);
    }
    // Swap: a new file (written beside and renamed in, as an operator should) is picked up.
    linear_model("naive_linear", 2.0f).save(dir.file("model.new"));
    std::filesystem::rename(dir.file("model.new"), model);
    std::this_thread::sleep_for(1500ms);
    // A broken file is refused; the node keeps predicting with model_b.
    std::ofstream(dir.file("broken")) << "{ not json";
    std::filesystem::rename(dir.file("broken"), model);
    std::this_thread::sleep_for(1500ms);
    predictions.clear();
    send(180, 90);
    std::this_thread::sleep_for(300ms);
    node.signal(SIGINT);
    EXPECT_EQ(node.wait_for(20000ms), std::optional<int>(0)) << dw::read_file(dir.file("node.err"));
    const auto got = predictions.samples();
    ASSERT_FALSE(got.empty());
    EXPECT_EQ(got.back().model_name(), "naive_linear");
    EXPECT_NEAR(got.back().force_n().z(), 2 * 2 * (-2.7 + 1.4), 1e-5);
    const auto err = dw::read_file(dir.file("node.err"));
    EXPECT_NE(err.find("model swapped: now naive_linear"), std::string::npos) << err;
    EXPECT_NE(err.find("not swapped"), std::string::npos) << err;
    EXPECT_NE(dw::read_file(dir.file("node.out")).find("1 model swaps"), std::string::npos);
}

// Issue 70: frames full of new body names grew the predictor from 62 to 458 MB. It remembers at
// most flight::kMaxBodies bodies (the least recently seen forgotten), and the ones flying keep
// their velocities.
TEST(PredictorOnline, FramesFullOfNewNamesHoldBoundedMemory) {
    FrameFeatures features("suff", {"v1", "v2"});
    constexpr int kFrames = 2000, kNewPerFrame = 4;
    std::optional<FrameNeighbours> f;
    for (int n = 0; n < kFrames; ++n) {
        auto frame = lab_frame(static_cast<std::uint64_t>(n), 1000.0 + n / 180.0);
        for (int k = 0; k < kNewPerFrame; ++k)
            dw::testkit::add_body(frame, "x" + std::to_string(n * kNewPerFrame + k), 1, 1, -1);
        f = features.update(frame);
    }
    EXPECT_LE(features.bodies_remembered(), dw::flight::kMaxBodies);
    EXPECT_GE(features.bodies_remembered(), 3u);
    ASSERT_TRUE(f.has_value());
    EXPECT_EQ(f->names, (std::vector<std::string>{"v1", "v2"}));
    // A neighbour that is no measurement (NaN, 1e300 from a wire) is not there; nor is a sufferer.
    auto frame = lab_frame(kFrames, 1000.0 + kFrames / 180.0);
    frame.bodies()[1].position_m().x(1e300);
    frame.bodies()[2].position_m().y(std::nan(""));
    f = features.update(frame);
    ASSERT_TRUE(f.has_value());
    EXPECT_TRUE(f->names.empty());
    frame.bodies()[0].position_m().z(std::nan(""));
    EXPECT_FALSE(features.update(frame).has_value());
}

// Online, each body is what the lab's meta.json says it is, as on a recorded flight: only its
// neighbours count (v3, tracked but not listed, does not), the learnt models see each one's mass,
// the physics each vehicle's parameters and the flying sufferer's own height.
TEST(PredictorOnline, EachBodyIsWhatTheLabsMetaJsonSaysItIs) {
    dw::test::TempDir dir;
    const OnlineBodies bodies = bodies_of_meta(lab_meta(dir, false));
    EXPECT_EQ(bodies.sufferer(), "suff");
    FrameFeatures features(bodies.sufferer(), bodies.neighbours());
    const auto f = features.update(lab_frame(0, 1000.0));
    ASSERT_TRUE(f.has_value());
    ASSERT_EQ(f->names, (std::vector<std::string>{"v1", "v2"}));
    EXPECT_DOUBLE_EQ(f->sufferer_height_m, 1.0);
    const Sample s = bodies.sample(*f);
    EXPECT_NEAR(mass_model().predict(s, bodies.source())[2], 0.067 + 0.032, 1e-6) << "v1 + v2";
    EXPECT_NEAR(mass_model().predict(f->x)[2], 0.0, 1e-6) << "no bodies known: every mass the training mean";
    // The physics: the same frame with v1 described as another vehicle (everything else the same)
    // pushes otherwise: each neighbour's jet is its own.
    const OnlineBodies other =
        bodies_of_meta(lab_meta(dir, false, "other.json",
                                R"({"mass_kg": 0.7, "rotors": 4, "prop_radius_m": 0.0635, "motor_distance_m": 0.25})"));
    const PhysicsModel physics(dw::physics::PhysicsConfig{});
    const double as_large = physics.predict(s, bodies.source())[2], as_other = physics.predict(s, other.source())[2];
    EXPECT_GT(std::abs(as_large - as_other), 1e-3 * std::abs(as_large)) << as_large << " vs " << as_other;
    // A body without parameters, or more neighbours than the models take: one clear error.
    std::ofstream(dir.file("bare.json")) << R"({"format": "downwash-flight/1", "sufferer": "suff", "neighbours": ["v1"],
        "formation": "free", "vehicles": {"suff": {"mass_kg": 0.032}}})";
    EXPECT_THROW(bodies_of_meta(dir.file("bare.json")), dw::InputError);
    std::ofstream(dir.file("many.json")) << R"({"format": "downwash-flight/1", "sufferer": "suff",
        "neighbours": ["a", "b", "c", "d"], "formation": "free", "vehicles": {}})";
    EXPECT_THROW(bodies_of_meta(dir.file("many.json")), dw::InputError);
}

// The same through the process: `dw-predictor run --vehicles meta.json`.
TEST(PredictorProcess, TakesTheLabsBodiesFromAMetaJson) {
    dw::test::TempDir dir;
    const auto model = dir.file("model.json");
    mass_model().save(model);
    const auto cfg = node_config("predbodies");
    dw::Subprocess node = start_node(dir, model, cfg, {"--vehicles", lab_meta(dir, true)});
    dw::dds::Participant p(cfg, "test");
    std::atomic<int> got{0};
    std::atomic<double> last_fd{0};
    dw::dds::Reader<dw::msg::WrenchPrediction> reader(p, dw::dds::topics::wrench_prediction,
                                                      [&](const auto& w, const auto&) {
                                                          last_fd = w.force_n().z();
                                                          ++got;
                                                      });
    dw::dds::Writer<dw::msg::MocapFrame> writer(p, dw::dds::topics::mocap_frame);
    ASSERT_TRUE(writer.wait_for_readers(1, 20000ms)) << dw::read_file(dir.file("node.err"));
    ASSERT_TRUE(reader.wait_for_writers(1, 20000ms));
    const auto deadline = std::chrono::steady_clock::now() + 20s;
    for (int i = 0; got.load() < 10 && std::chrono::steady_clock::now() < deadline; ++i) {
        auto f = lab_frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0);
        writer.write(f);
        std::this_thread::sleep_for(std::chrono::microseconds(5556));
    }
    std::this_thread::sleep_for(300ms);
    node.signal(SIGINT);
    EXPECT_EQ(node.wait_for(20000ms), std::optional<int>(0)) << dw::read_file(dir.file("node.err"));
    ASSERT_GT(got.load(), 0) << dw::read_file(dir.file("node.err"));
    EXPECT_NEAR(last_fd.load(), 0.067 + 0.032, 1e-6);
    EXPECT_NE(dw::read_file(dir.file("node.err")).find("for 'suff', each body as"), std::string::npos);
    // A meta.json that is not one, and a sufferer named twice: one line each, saying what, exit 2.
    std::ofstream(dir.file("bad.json"))
        << R"({"format": "downwash-flight/1", "sufferer": "suff", "formation": "free", "neighbours": 3})";
    const std::vector<std::pair<std::vector<std::string>, std::string>> bad{
        {{"--vehicles", dir.file("bad.json")}, "bad.json: field 'neighbours'"},
        {{"--vehicles", dir.file("meta.json"), "--sufferer", "s"}, "--sufferer excludes --vehicles"}};
    for (const auto& [extra, what] : bad) {
        std::vector<std::string> args{dw::test::bin("dw-predictor"), "run", "--model", model};
        args.insert(args.end(), extra.begin(), extra.end());
        const auto r = dw::test::run(args, dir);
        EXPECT_EQ(r.status, 2) << r.err;
        EXPECT_EQ(dw::test::lines(r.err).size(), 1u) << r.err;
        EXPECT_NE(r.err.find(what), std::string::npos) << r.err;
    }
}

TEST(PredictorProcess, BadModelIsOneLineAndExit2) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("m.json")) << "{\"format\": \"" << kModelFormat << "\"}";
    const auto r = dw::test::run({dw::test::bin("dw-predictor"), "run", "--model", dir.file("m.json")}, dir);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(dw::test::lines(r.err).size(), 1u) << r.err;
    EXPECT_NE(r.err.find("kind"), std::string::npos) << r.err;
    const auto r2 = dw::test::run({dw::test::bin("dw-predictor"), "map", "--models", dir.file("none.json")}, dir);
    EXPECT_EQ(r2.status, 2);
    EXPECT_EQ(dw::test::lines(r2.err).size(), 1u) << r2.err;
}

// CI found it (soak): the predictor writes from its mocap callback, and its first prediction waits
// for the recorder (--await-readers). Waiting on Fast DDS's reception thread overflowed the mocap
// reader's history: 235 frames lost at every start. It waits before it subscribes now.
TEST(PredictorProcess, AwaitingTheRecorderLosesNoMocapFrame) {
    dw::test::TempDir dir;
    const auto model = dir.file("model.json");
    linear_model("learnt_linear", 1.0f).save(model);
    const auto cfg = node_config("predawait");
    dw::Subprocess node = start_node(dir, model, cfg, {"--await-readers", "recorder", "--await-timeout", "30"});
    dw::dds::Participant bridge(cfg, "mocap_bridge");
    dw::dds::Writer<dw::msg::MocapFrame> writer(bridge, dw::dds::topics::mocap_frame);
    std::atomic<bool> stop{false};
    std::thread publisher([&] {
        for (int i = 0; !stop; ++i) {
            auto f = frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, -1.0 + 0.5 * i / 180.0);
            writer.write(f);
            std::this_thread::sleep_for(std::chrono::microseconds(5556));
        }
    });
    // Let the predictor start and (before the fix) block on its first prediction for a while.
    std::this_thread::sleep_for(3000ms);
    dw::dds::Participant recorder(cfg, "recorder");
    std::atomic<int> got{0};
    dw::dds::Reader<dw::msg::WrenchPrediction> reader(recorder, dw::dds::topics::wrench_prediction,
                                                      [&](const auto&, const auto&) { ++got; });
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (got.load() < 360 && std::chrono::steady_clock::now() < deadline) std::this_thread::sleep_for(20ms);
    const bool predicted = got.load() >= 360;
    stop = true;
    publisher.join();
    node.signal(SIGINT);
    EXPECT_EQ(node.wait_for(20000ms), std::optional<int>(0)) << dw::read_file(dir.file("node.err"));
    ASSERT_TRUE(predicted) << got.load() << " predictions; " << dw::read_file(dir.file("node.err"));
    const auto out = dw::read_file(dir.file("node.out"));
    EXPECT_NE(out.find(" 0 mocap frames lost, 0 frames the model could not predict"), std::string::npos) << out;
}

// The training is a module beside the executable, loaded when a model is first trained (libtorch
// made every start cost ~0.5 s of CPU): without it, training ends in one line and exit 1, and
// everything else still works.
TEST(PredictorProcess, WithoutItsTrainingModuleItStillServesAndTrainingIsOneLineExit1) {
    dw::test::TempDir dir;
    const std::string alone = dir.file("dw-predictor");
    std::filesystem::copy_file(dw::test::bin("dw-predictor"), alone);
    std::filesystem::permissions(alone, std::filesystem::perms::owner_exec, std::filesystem::perm_options::add);
    const auto help = dw::test::run({alone, "--help"}, dir);
    EXPECT_EQ(help.status, 0) << help.err;
    const auto r = dw::test::run({alone, "study", "--legs", "5", "--epochs", "1", "--out", dir.file("s")}, dir);
    EXPECT_EQ(r.status, 1) << r.err;
    const auto l = dw::test::lines(r.err);
    ASSERT_FALSE(l.empty());
    EXPECT_NE(l.back().find("error: cannot load the training module: "), std::string::npos) << r.err;
    EXPECT_NE(l.back().find("libdw_torch_train.so"), std::string::npos) << l.back();
    EXPECT_EQ(
        std::count_if(l.begin(), l.end(), [](const std::string& s) { return s.find("error:") != std::string::npos; }),
        1)
        << r.err;
}

// Issue 70: what the online predictor publishes for 30 frames with model file `model` (frame i
// made by `make`), and how many frames it left unpredicted.
namespace {
struct Published {
    std::vector<dw::msg::WrenchPrediction> predictions;
    std::uint64_t unpredicted = 0, stray_stamps = 0;
};
Published publish_frames(const std::string& model, const std::string& name,
                         const std::function<dw::msg::MocapFrame(int)>& make) {
    const auto cfg = node_config(name);
    dw::dds::Participant p(cfg, "test");
    dw::test::Collected<dw::msg::WrenchPrediction> predictions(p, dw::dds::topics::wrench_prediction);
    NodeOptions o;
    o.model_path = model;
    PredictorNode node(p, o, dw::SystemClock::instance());
    dw::dds::Writer<dw::msg::MocapFrame> writer(p, dw::dds::topics::mocap_frame);
    EXPECT_TRUE(writer.wait_for_readers(1, 20000ms));
    for (int i = 0; i < 30; ++i) {
        auto f = make(i);
        writer.write(f);
        std::this_thread::sleep_for(5ms);
    }
    std::this_thread::sleep_for(300ms);
    return {predictions.samples(), node.unpredicted(), node.stray_stamps()};
}
}  // namespace

// A frame whose stamp is off the frames' own time (a garbled or forged word: 1e6 s ahead) was
// predicted and published at that time; now it is refused and counted, and the frames around it
// are predicted as before. A stream whose clock moves for good (Motive restarted) is followed.
TEST(PredictorOnline, AFrameStampedOffTheFramesTimeIsRefused) {
    dw::test::TempDir dir;
    const auto model = dir.file("model.json");
    linear_model("learnt_linear", 1.0f).save(model);
    const auto r = publish_frames(model, "stray", [](int i) {
        const double t = i == 10 ? 1e6 : i < 20 ? 1000.0 + i / 180.0 : 5.0 + i / 180.0;  // at 20: restarted
        return frame(static_cast<std::uint64_t>(i), t, 0.3);
    });
    std::size_t after_restart = 0;
    for (const auto& w : r.predictions) {
        const double t = dw::dds::from_msg(w.header().stamp()) * 1e-9;
        EXPECT_LT(t, 1e5) << "a prediction at the stray stamp";
        after_restart += t < 100;
    }
    EXPECT_GE(r.predictions.size(), 20u);  // best effort on loopback
    EXPECT_GE(after_restart, 3u) << "the restarted stream was not followed";
    // The stray and the restarted stream's first kStampsToFollow - 1 (best effort: one may be lost).
    EXPECT_GE(r.stray_stamps, static_cast<std::uint64_t>(dw::kStampsToFollow - 1));
    EXPECT_LE(r.stray_stamps, static_cast<std::uint64_t>(dw::kStampsToFollow));
}

// Issue 71, item 4: each online prediction carries its 95 % interval on f_d from the physics' noise
// model — the sufferer's vehicle class's calibrated floor and the turbulence: 1.96 sqrt(floor² +
// (2 I f_d)²); a learnt model with no physics to take it from carries none (0).
TEST(PredictorOnline, EachPredictionCarriesItsIntervalFromThePhysicsNoiseModel) {
    dw::test::TempDir dir;
    dw::physics::PhysicsConfig physics;
    physics.turbulence.enabled = true;
    physics.turbulence.intensity = 0.1;
    physics.classes.push_back({"the lab's sufferer", physics.sufferer.vehicle, physics.bauersfeld, 1.18, 0.1, 0.02});
    dw::write_file(dir.file("physics.yaml"), dw::physics::to_yaml(physics));
    const auto with = publish_frames(dir.file("physics.yaml"), "interval", [](int i) {
        return frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, 0.2);
    });
    ASSERT_GE(with.predictions.size(), 20u);  // best effort on loopback
    for (const auto& w : with.predictions) {
        const double f_d = w.force_n().z(), turbulent = 2 * 0.1 * f_d;
        EXPECT_NEAR(w.f_d_interval_n(), dw::kZ95 * std::sqrt(0.02 * 0.02 + turbulent * turbulent), 1e-12);
    }
    linear_model("learnt_linear", 1.0f).save(dir.file("model.json"));
    const auto without = publish_frames(dir.file("model.json"), "nointerval", [](int i) {
        return frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, 0.2);
    });
    ASSERT_FALSE(without.predictions.empty());
    for (const auto& w : without.predictions) EXPECT_EQ(w.f_d_interval_n(), 0.0);
}

// The online predictor never publishes a non-finite value — neither for a body at NaN nor for a
// model whose weights overflow (1e30 x an offset in float): those frames are left unpredicted and
// counted.
TEST(PredictorOnline, NeverPublishesANonFiniteWrench) {
    dw::test::TempDir dir;
    const auto model = dir.file("huge.json");
    auto huge = linear_model("learnt_linear", 9e29f);       // about the largest weight a model file may hold
    for (int k = 0; k < 3; ++k) huge.input_std[k] = 1e-9f;  // the offsets / 1e-9 x 9e29: beyond float's range
    huge.save(model);
    const auto r = publish_frames(model, "nonfinite", [](int i) {
        auto f = frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, 0.0);  // every offset overflows
        if (i % 3 == 1) f.bodies()[1].position_m().x(std::nan(""));              // and a NaN body
        return f;
    });
    EXPECT_GE(r.unpredicted, 25u);  // best effort on loopback; each frame is non-finite one way
    EXPECT_TRUE(r.predictions.empty());
}
// ... nor a finite wrench no stand could measure (physics::plausible_wrench): a model whose weights
// are large but finite predicts 1e7 N for every frame, and none of it reaches the wire.
TEST(PredictorOnline, NeverPublishesAWrenchNoStandCouldMeasure) {
    dw::test::TempDir dir;
    const auto model = dir.file("large.json");
    linear_model("learnt_linear", 1e8f).save(model);  // 1e8 x the offsets (0.3-0.5 m): 1e7 N
    const auto r = publish_frames(model, "implausible",
                                  [](int i) { return frame(static_cast<std::uint64_t>(i), 1000.0 + i / 180.0, 0.3); });
    EXPECT_GE(r.unpredicted, 25u);  // best effort on loopback
    EXPECT_TRUE(r.predictions.empty());
}
