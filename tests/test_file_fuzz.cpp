// Issue 43: a mutation fuzzer for every file parser the tools share — flight folders, MCAP
// recordings (strict, salvage, recover, and the flight a recording holds), Neural-Swarm logs (CSV
// and binary), YAML configuration (physics, lab), learnt model files. Each seed file is damaged many ways (bytes
// flipped, cut, hostile tokens inserted, lines repeated or dropped); the parser must answer with
// dw::InputError in one line of at most 200 characters (paths aside) or read the file — never
// another exception, a crash or a sanitizer report (scripts/sanitize.sh runs this executable).
// FileFuzz.* runs a small number of mutations per parser; FileFuzzFull.* the full count (--full).
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>
#include <vector>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "dds/time.hpp"
#include "flight/flight.hpp"
#include "importer/neural_swarm.hpp"
#include "lab/labfile.hpp"
#include "mcap/mcap.hpp"
#include "physics/config.hpp"
#include "physics/flight_sim.hpp"
#include "predictor/model.hpp"
#include "probe/samples.hpp"
#include "real_data.hpp"
#include "recordings/recordings.hpp"
#include "support.hpp"
#include "testkit/mlp.hpp"
#include "testkit/mocap.hpp"
#include "testkit/recording.hpp"

namespace fs = std::filesystem;

namespace {

constexpr int kSmall = 150;  // mutations per seed file by default
constexpr int kFull = 3000;  // under --full (FileFuzzFull.*)
constexpr std::size_t kMaxMessage = 200;

// Values a hostile user tries in text files.
const std::vector<std::string> kTokens = {"1e308",
                                          "-1e308",
                                          "1e400",
                                          "nan",
                                          "inf",
                                          "-0",
                                          "99999999999999999999",
                                          "4294967297",
                                          ",",
                                          "\n",
                                          "\r",
                                          "\"",
                                          "[[[[[[[[",
                                          "{{{{",
                                          "*a",
                                          "&a ",
                                          "---\n",
                                          "\xff\xfe",
                                          std::string(1, '\0'),
                                          "  ",
                                          "1e-320",
                                          "0x10",
                                          ":"};

// One damaged copy of `seed`.
std::string mutate(const std::string& seed, std::mt19937_64& rng) {
    std::string s = seed;
    auto at = [&](std::size_t n) { return n == 0 ? 0 : static_cast<std::size_t>(rng() % n); };
    const int kinds = 1 + static_cast<int>(rng() % 3);
    for (int k = 0; k < kinds; ++k) {
        switch (rng() % 6) {
            case 0:  // flip bytes
                for (int i = 0; i < 1 + static_cast<int>(rng() % 6) && !s.empty(); ++i)
                    s[at(s.size())] ^= static_cast<char>(1 + rng() % 255);
                break;
            case 1: s.resize(at(s.size() + 1)); break;  // cut
            case 2: s.insert(at(s.size() + 1), kTokens[at(kTokens.size())]); break;
            case 3: {  // replace a run of digits or letters by a token
                const std::size_t p = at(s.size() + 1), n = at(12);
                s.replace(std::min(p, s.size()), n, kTokens[at(kTokens.size())]);
                break;
            }
            case 4: {  // repeat a stretch (lines, records, keys)
                const std::size_t p = at(s.size() + 1), n = std::min(at(400), s.size() - std::min(p, s.size()));
                s.insert(p, s.substr(std::min(p, s.size()), n));
                break;
            }
            default: {  // drop a stretch
                const std::size_t p = at(s.size() + 1);
                s.erase(std::min(p, s.size()), at(200));
                break;
            }
        }
    }
    return s;
}

std::string bytes_of(const std::string& path) { return dw::read_file(path, "seed"); }
void put(const std::string& path, const std::string& bytes) {
    std::ofstream(path, std::ios::binary).write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Runs `parse` on `mutations` damaged versions of each seed file (written to `target` first).
// Any exception but dw::InputError, or an error of more than one line or kMaxMessage characters
// (the temporary folder's path not counted), fails, naming the mutation to replay it.
struct Fuzz {
    const dw::test::TempDir& dir;
    int mutations;
    std::uint64_t seed = 20261127;
    int refused = 0, read = 0;

    void run(const std::string& target, const std::vector<std::string>& seeds, const std::function<void()>& parse) {
        std::mt19937_64 rng(seed);
        for (int m = 0; m < mutations; ++m) {
            const std::string& original = seeds[static_cast<std::size_t>(m) % seeds.size()];
            const std::string damaged = mutate(original, rng);
            put(target, damaged);
            if (std::getenv("DW_FUZZ_TRACE")) std::fprintf(stderr, "%s %d\n", target.c_str(), m);
            try {
                parse();
                ++read;
            } catch (const dw::InputError& e) {
                ++refused;
                check_message(e.what(), target, m);
            } catch (const std::exception& e) {
                put(dir.file("failing-input"), damaged);
                FAIL() << target << ", mutation " << m << ": " << typeid(e).name() << ": " << e.what()
                       << " (input kept as failing-input)";
            }
        }
    }
    void check_message(std::string what, const std::string& target, int m) const {
        EXPECT_EQ(what.find('\n'), std::string::npos) << target << ", mutation " << m << ": " << what.substr(0, 300);
        const std::string root = dir.file("");
        for (auto p = what.find(root); p != std::string::npos; p = what.find(root)) what.erase(p, root.size());
        EXPECT_LE(what.size(), kMaxMessage) << target << ", mutation " << m << ": " << what.substr(0, 300);
    }
};

// A small simulated flight (two legs), written as a flight folder.
dw::flight::Flight small_flight() {
    dw::physics::FlyOptions fo;
    fo.grid.legs = 2;
    return dw::physics::simulate_flight(dw::physics::PhysicsConfig{}, fo).flight;
}

void flight_folder(int mutations) {
    dw::test::TempDir d;
    const std::string dir = d.file("f");
    const auto flight = small_flight();
    Fuzz fuzz{d, mutations};
    for (const std::string file : {"meta.json", "wrench.csv", "poses.csv", "legs.csv"}) {
        dw::flight::write_flight(flight, dir);
        const std::string seed = bytes_of(dir + "/" + file);
        fuzz.run(dir + "/" + file, {seed}, [&] { (void)dw::flight::read_flight(dir); });
        put(dir + "/" + file, seed);
    }
    EXPECT_GT(fuzz.refused, 0);
    EXPECT_GT(fuzz.read, 0) << "some mutations (a changed digit) still read";
}

// A recording of the lab's stand and mocap topics, as the recorder writes it.
std::string lab_recording(const dw::test::TempDir& d, dw::mcap::Compression c) {
    const std::string path = d.file("seed.mcap");
    dw::testkit::LabRecording rec(path, c);
    const auto w = rec.channel(dw::dds::topics::stand_wrench), m = rec.channel(dw::dds::topics::mocap_frame);
    std::uint32_t seq = 0;
    for (std::size_t i = 0; i < 120; ++i) {
        auto s = dw::probe::make_sample<dw::msg::WrenchStamped>(i);
        rec.write(w, seq++, 1'000'000'000ull + i * 12'500'000ull, s);
    }
    for (std::size_t i = 0; i < 240; ++i) {  // 180 Hz, on the wrench samples' clock (make_sample's stamps)
        dw::msg::MocapFrame f;
        const auto t = static_cast<dw::Nanos>(1'700'000'000'000'000'000 + i * 5'555'555ull);
        f.header().stamp(dw::dds::to_msg(t));
        dw::testkit::add_body(f, "sufferer", 0, 0, -1.4);
        dw::testkit::add_body(f, "v1", 0.01 * static_cast<double>(i), -1.0, -1.7);
        rec.write(m, seq++, 1'000'000'000ull + i * 5'555'555ull, f);
    }
    rec.close();
    return bytes_of(path);
}

void mcap_files(int mutations) {
    dw::test::TempDir d;
    std::vector<std::string> seeds;
    for (const auto c : {dw::mcap::Compression::none, dw::mcap::Compression::zstd, dw::mcap::Compression::lz4})
        seeds.push_back(lab_recording(d, c));
    const std::string file = d.file("f.mcap");
    Fuzz fuzz{d, mutations};
    fuzz.run(file, seeds, [&] {
        dw::mcap::WriterOptions o;
        o.fsync = false;
        (void)dw::mcap::recover(file, d.file("out.mcap"), o);
        (void)dw::recordings::flight_from_recording(d.file("out.mcap"), {});
    });
    EXPECT_GT(fuzz.refused, 0);
}

void neural_swarm_logs(int mutations) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    std::string csv = bytes_of(dw::test::kNeuralSwarm + "swap_ss/cf50_01.csv");
    std::size_t cut = 0;
    for (int line = 0; line < 120 && cut != std::string::npos; ++line) cut = csv.find('\n', cut + 1);
    csv.resize(std::min(cut, csv.size()));
    const std::string binary = bytes_of(dw::test::kNeuralSwarm + "randomwalk_ss/cf50_02").substr(0, 24000);
    Fuzz fuzz{d, mutations};
    fuzz.run(d.file("cf50_01.csv"), {csv}, [&] { (void)dw::importer::read_neural_swarm_log(d.file("cf50_01.csv")); });
    fuzz.run(d.file("cf50_02"), {binary}, [&] { (void)dw::importer::read_neural_swarm_log(d.file("cf50_02")); });
    EXPECT_GT(fuzz.refused, 0);
}

void yaml_configuration(int mutations) {
    dw::test::TempDir d;
    const std::string physics = bytes_of(std::string(DW_SOURCE_DIR) + "/config/physics.crazyflie.yaml");
    const std::string lab = bytes_of(std::string(DW_SOURCE_DIR) + "/config/lab.sim.yaml");
    Fuzz fuzz{d, mutations};
    fuzz.run(d.file("p.yaml"), {physics}, [&] { (void)dw::physics::load_physics(d.file("p.yaml")); });
    fuzz.run(d.file("lab.yaml"), {lab}, [&] { (void)dw::lab::load_lab(d.file("lab.yaml")); });
    EXPECT_GT(fuzz.refused, 0);
}

// A learnt model with every part a file can hold: Deep Sets' phi and rho on a sum model's baseline.
std::string model_seed(const dw::test::TempDir& d) {
    using namespace dw::predictor;
    LearntModel m;
    m.kind = "deep_sets";
    m.structure = Structure::deep_sets;
    m.input_mean.fill(0.0F);
    m.input_std.fill(1.0F);
    m.output_scale.fill(0.05F);
    std::mt19937 rng(43);
    m.phi = dw::testkit::random_mlp(rng, {kFeatureSize, 4, 3}, 0.1F);
    m.rho = dw::testkit::random_mlp(rng, {3, 4, 6}, 0.1F);
    m.baseline = dw::testkit::random_mlp(rng, {kFeatureSize, 4, 6}, 0.1F);
    m.save(d.file("seed.json"));
    return bytes_of(d.file("seed.json"));
}

void model_files(int mutations) {
    dw::test::TempDir d;
    const std::string seed = model_seed(d);
    const std::vector<dw::predictor::RelState> neighbours = {{0.1, 0.0, -0.5, 0, 0, 0}, {-0.2, 0.1, -0.8, 0, 0, 0}};
    Fuzz fuzz{d, mutations};
    fuzz.run(d.file("model.json"), {seed}, [&] {  // read, then used: its shapes must fit what it is fed
        (void)dw::predictor::LearntModel::load(d.file("model.json")).predict(neighbours);
    });
    EXPECT_GT(fuzz.refused, 0);
}

}  // namespace

TEST(FileFuzz, FlightFolders) { flight_folder(kSmall); }
TEST(FileFuzz, McapRecordings) { mcap_files(kSmall); }
TEST(FileFuzz, NeuralSwarmLogs) { neural_swarm_logs(kSmall); }
TEST(FileFuzz, YamlConfiguration) { yaml_configuration(kSmall); }
TEST(FileFuzz, ModelFiles) { model_files(kSmall); }

TEST(FileFuzzFull, FlightFolders) { flight_folder(kFull); }
TEST(FileFuzzFull, McapRecordings) { mcap_files(kFull); }
TEST(FileFuzzFull, NeuralSwarmLogs) { neural_swarm_logs(kFull); }
TEST(FileFuzzFull, YamlConfiguration) { yaml_configuration(kFull); }
TEST(FileFuzzFull, ModelFiles) { model_files(kFull); }
