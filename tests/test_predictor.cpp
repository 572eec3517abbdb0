// The predictor: datasets from flight folders (alignment, split by leg), models (save/load,
// permutation invariance, bad files), the arena metric, the pixel test of the maps, and the
// study's claims on simulated flights (Deep Sets vs the linear models).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <opencv2/imgcodecs.hpp>
#include <nlohmann/json.hpp>
#include <random>
#include <set>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "physics/flight_sim.hpp"
#include "predictor/dataset.hpp"
#include "predictor/evaluate.hpp"
#include "predictor/maps.hpp"
#include "predictor/model.hpp"
#include "predictor/regimes.hpp"
#include "predictor/study.hpp"
#include "predictor/intervals.hpp"
#include "predictor/train.hpp"
#include "support.hpp"
#include "testkit/mlp.hpp"

using namespace dw::predictor;

namespace {

// A small simulated flight folder (2 neighbours, few legs).
std::string small_flight(const dw::test::TempDir& dir, const std::string& formation = "leader_follower",
                         int legs = 10) {
    dw::physics::FlyOptions fly;
    fly.formation = formation;
    fly.grid.legs = legs;
    fly.grid.altitudes_m = {0.8};
    const auto path = dir.file(formation);
    dw::flight::write_flight(dw::physics::simulate_flight(dw::physics::PhysicsConfig{}, fly).flight, path);
    return path;
}

LearntModel random_model(Structure s, unsigned seed) {
    std::mt19937 rng(seed);
    LearntModel m;
    m.kind = s == Structure::sum ? "learnt_linear" : "deep_sets";
    m.structure = s;
    m.input_mean = {0.1f, -0.2f, -1.0f, 0, 0.3f, 0, 0.8f, 0.6f, 1.2f, 0.7f, 0.7f, 0};  // jet_overlap: 0 and 1
    m.input_std = {0.6f, 0.7f, 0.4f, 0.1f, 0.5f, 0.1f, 0.5f, 0.4f, 0.6f, 0.1f, 0.1f, 1};
    m.output_scale = {0.1f, 0.1f, 1.5f, 0.01f, 0.01f, 0.005f};
    m.phi = dw::testkit::random_mlp(rng, {kFeatureSize, 16, 16, s == Structure::sum ? 6 : 8}, 0.5f);
    if (s == Structure::deep_sets) m.rho = dw::testkit::random_mlp(rng, {8, 16, 6}, 0.5f);
    return m;
}

}  // namespace

TEST(PredictorDataset, AlignsPosesWithTheWrenchAndSplitsByLeg) {
    dw::test::TempDir dir;
    const auto path = small_flight(dir);
    const auto f = dw::flight::read_flight(path);
    const Dataset d = load_dataset(path);
    ASSERT_EQ(d.sources.size(), 1u);
    EXPECT_EQ(d.sources[0].formation, "leader_follower K=2");
    for (std::size_t a = 0; a < 6; ++a) EXPECT_TRUE(d.sources[0].measured[a]) << "a stand measures axis " << a;
    ASSERT_GT(d.samples.size(), 1000u);
    // Every sample's relative position is the interpolated poses' difference at the wrench time.
    const auto tr = dw::flight::tracks(f);
    const auto& s = d.samples[d.samples.size() / 2];
    ASSERT_EQ(s.k, 2);
    const auto ps = tr[static_cast<std::size_t>(f.find_body("sufferer"))].position_at(s.t);
    const auto p1 = tr[static_cast<std::size_t>(f.find_body(f.meta.neighbours[0]))].position_at(s.t);
    for (std::size_t a = 0; a < 3; ++a) EXPECT_NEAR(s.x[0][a], p1[a] - ps[a], 1e-9);
    // Velocities of vehicles flying a leg at 0.5 m/s along E (they lag the reference a little
    // at the legs' ends).
    int on_leg = 0, at_speed = 0;
    for (const auto& x : d.samples)
        if (x.leg >= 0) {
            ++on_leg;
            at_speed += std::abs(std::abs(x.x[0][4]) - 0.5) < 0.05;
            EXPECT_EQ(x.leg_direction, x.x[0][4] > 0 ? 1 : -1);
        }
    EXPECT_GT(on_leg, 500);
    EXPECT_GT(at_speed, 0.8 * on_leg);
    const Split sp = split_by_leg(d);
    std::set<int> tr_legs, te_legs;
    for (const auto& x : sp.train.samples) tr_legs.insert(x.leg);
    for (const auto& x : sp.test.samples) te_legs.insert(x.leg);
    EXPECT_EQ(te_legs, (std::set<int>{0, 5}));
    for (int l : te_legs) EXPECT_EQ(tr_legs.count(l), 0u);
    EXPECT_EQ(sp.train.samples.size() + sp.validation.samples.size() + sp.test.samples.size(),
              static_cast<std::size_t>(on_leg));
}

// Issue 42: a flight whose poses are the vehicles' own estimates (meta.json pose_source) is
// carried into the dataset, and the tables say which flights those are; motion capture needs no note.
TEST(PredictorDataset, SaysWhichFlightsPosesAreEstimates) {
    dw::test::TempDir dir;
    const auto path = small_flight(dir);
    auto f = dw::flight::read_flight(path);
    EXPECT_EQ(dw::predictor::poses_note(load_dataset(path)), "");
    f.meta.pose_source = dw::flight::PoseSource::estimate;
    dw::flight::write_flight(f, dir.file("estimated"));
    Dataset d = load_dataset(path);
    d.append(load_dataset(dir.file("estimated")));
    ASSERT_EQ(d.sources.size(), 2u);
    EXPECT_FALSE(d.sources[0].estimated_poses);
    EXPECT_TRUE(d.sources[1].estimated_poses);
    const std::string note = dw::predictor::poses_note(d);
    EXPECT_NE(note.find("The poses of 1 flight(s) are the vehicles' own state estimates"), std::string::npos) << note;
    EXPECT_NE(note.find("estimated"), std::string::npos) << note;
}

TEST(PredictorDataset, FindsLegsWithoutLegsCsv) {
    dw::test::TempDir dir;
    auto f = dw::flight::read_flight(small_flight(dir));
    const auto truth = *f.legs;
    const auto found = dw::flight::find_legs(f);
    ASSERT_EQ(found.size(), truth.size());
    for (std::size_t i = 0; i < found.size(); ++i) {
        // The vehicles lag the reference a little; the found leg covers most of the true one
        // and little else.
        const double overlap = std::min(found[i].t_end, truth[i].t_end) - std::max(found[i].t_start, truth[i].t_start);
        const double length = truth[i].t_end - truth[i].t_start;
        EXPECT_GT(overlap, 0.7 * length) << "leg " << i;
        EXPECT_LT(found[i].t_end - found[i].t_start, length + 2.5) << "leg " << i;
    }
}

TEST(PredictorDataset, RejectsWhatIsNotAFlight) {
    dw::test::TempDir dir;
    std::ofstream(dir.file("x.txt")) << "hello";
    EXPECT_THROW(load_dataset(dir.file("x.txt")), dw::InputError);
    EXPECT_THROW(load_dataset(dir.file("missing")), dw::InputError);
    std::filesystem::create_directories(dir.file("bad"));
    std::ofstream(dir.file("bad/meta.json")) << "{";
    try {
        load_dataset(dir.file("bad"));
        FAIL();
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("meta.json"), std::string::npos) << e.what();
    }
}

TEST(PredictorModel, SavesAndLoadsExactlyAndIsPermutationInvariant) {
    dw::test::TempDir dir;
    for (auto s : {Structure::sum, Structure::deep_sets}) {
        const LearntModel m = random_model(s, 7);
        m.save(dir.file("m.json"));
        const LearntModel back = LearntModel::load(dir.file("m.json"));
        const std::vector<RelState> x{
            {0.1, 0.5, -1.2, 0, 0.5, 0}, {0.0, -0.5, -1.3, 0, 0.5, 0}, {0.3, 0, -1.25, 0.1, 0.4, 0}};
        const std::vector<RelState> y{x[2], x[0], x[1]};
        const auto a = m.predict(x), b = back.predict(x), c = m.predict(y);
        for (std::size_t i = 0; i < 6; ++i) {
            EXPECT_FLOAT_EQ(static_cast<float>(a[i]), static_cast<float>(b[i]));
            EXPECT_NEAR(a[i], c[i], 1e-5 * (1 + std::abs(a[i])));
        }
        // The sum structure gives nothing with nobody near; Deep Sets gives rho(0).
        if (s == Structure::sum)
            for (double v : m.predict({})) EXPECT_EQ(v, 0.0);
        // A sum of single-neighbour predictions is exactly the sum structure.
        if (s == Structure::sum) {
            const auto s0 = m.predict({&x[0], 1}), s1 = m.predict({&x[1], 1}), s2 = m.predict({&x[2], 1});
            for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(a[i], s0[i] + s1[i] + s2[i], 1e-4 * (1 + std::abs(a[i])));
        }
    }
}

TEST(PredictorModel, FeaturesCarryTheJetsInvariantsTheMassesAndStayFinite) {
    const Features f = features_of({0.3, 0.4, -1.2, 0.1, 0.5, 0}, 0.032, 0.067);
    for (std::size_t a = 0; a < 6; ++a) EXPECT_EQ(f[a], (RelState{0.3, 0.4, -1.2, 0.1, 0.5, 0})[a]);
    EXPECT_NEAR(f[6], 0.5, 1e-12);                                      // horizontal distance
    EXPECT_NEAR(f[7], 0.5 / (1.2 + kFeatureSeparationOffsetM), 1e-12);  // distance over separation
    EXPECT_NEAR(f[8], 1 / (1.2 + kFeatureSeparationOffsetM), 1e-12);
    EXPECT_EQ(f[kNeighbourMassFeature], 0.032);
    EXPECT_EQ(f[kSuffererMassFeature], 0.067);
    for (double v : features_of({0.2, 0, 0, 0, 0, 0}, 0.7, 0.7))
        EXPECT_TRUE(std::isfinite(v)) << "a neighbour level with the sufferer";
    // Mirror images across the sufferer's vertical axis share the invariant features.
    const Features g = features_of({-0.3, -0.4, -1.2, 0.1, 0.5, 0}, 0.032, 0.067);
    for (std::size_t a = 6; a < f.size(); ++a) EXPECT_EQ(f[a], g[a]);
    EXPECT_TRUE(std::isnan(features_of({0.3, 0.4, -1.2, 0, 0, 0})[kNeighbourMassFeature])) << "unknown: NaN";
}

// The masses tell a small neighbour's jet from a large one's (issue 41: relative states alone
// cannot); where they are not known (a bare set of relative states) the model serves its training
// set's mean mass, and a flight's sample gives each neighbour its own (meta.json's parameters).
TEST(PredictorModel, AModelSeesEachBodysMassAndServesTheMeanWhereItIsUnknown) {
    LearntModel m = random_model(Structure::sum, 11);
    m.input_mean[kNeighbourMassFeature] = 0.05f, m.input_std[kNeighbourMassFeature] = 0.02f;
    m.input_mean[kSuffererMassFeature] = 0.05f, m.input_std[kSuffererMassFeature] = 0.02f;
    const std::vector<RelState> x{{0.1, 0.2, -0.6, 0, 0, 0}};
    Bodies small, large, mean;
    small.sufferer_kg = large.sufferer_kg = mean.sufferer_kg = 0.05;
    small.neighbour_kg[0] = 0.032, large.neighbour_kg[0] = 0.067, mean.neighbour_kg[0] = 0.05;
    const auto ps = m.predict(x, small), pl = m.predict(x, large), pm = m.predict(x, mean), pu = m.predict(x);
    EXPECT_GT(std::abs(ps[2] - pl[2]), 1e-6) << "the neighbour's mass changes nothing";
    for (std::size_t a = 0; a < 6; ++a) EXPECT_NEAR(pu[a], pm[a], 1e-5) << "unknown is not the mean, axis " << a;
    Source src;
    src.sufferer.mass_kg = 0.05;
    src.neighbours = {{}, {}};
    src.neighbours[1].mass_kg = 0.067;
    Sample s;
    s.k = 1, s.x[0] = x[0], s.who[0] = 1;  // the source's second neighbour
    const auto b = bodies_of(s, src);
    EXPECT_EQ(b.neighbour_kg[0], 0.067);
    EXPECT_EQ(b.sufferer_kg, 0.05);
    const auto pf = m.predict(s, src);
    for (std::size_t a = 0; a < 6; ++a) EXPECT_NEAR(pf[a], pl[a], 1e-6) << "a flight's sample, axis " << a;
    // Trained where every vehicle had one mass, the model learnt nothing from it: another mass
    // served changes nothing (train_torch.cpp's normalisation saves that spread as kUnvariedStd).
    m.input_std[kNeighbourMassFeature] = m.input_std[kSuffererMassFeature] = kUnvariedStd;
    Bodies heavy = small;
    heavy.neighbour_kg[0] = heavy.sufferer_kg = 0.7;
    const auto p1 = m.predict(x, small), p2 = m.predict(x, heavy);
    for (std::size_t a = 0; a < 6; ++a) EXPECT_NEAR(p1[a], p2[a], 1e-6) << "an unvaried mass weighs, axis " << a;
}

TEST(PredictorModel, JetOverlapIsOneForStackedJetsAndVanishesForDistantOnes) {
    const RelState a{0.2, 0.0, -1.2, 0, 0.5, 0}, b{0.2, 0.4, -1.2, 0, 0.5, 0};
    EXPECT_EQ(features_of(a)[kOverlapFeature], 0.0) << "a neighbour alone overlaps nothing";
    // 0.4 m apart, both 1.2 m up: q = 0.4 / (2.4 + 0.2) / 0.2.
    const double q = 0.4 / (2 * (1.2 + kFeatureSeparationOffsetM)) / kJetOverlapRatio;
    EXPECT_NEAR(jet_overlap(a, b), std::exp(-q * q), 1e-12);
    EXPECT_EQ(jet_overlap(a, b), jet_overlap(b, a));
    EXPECT_NEAR(jet_overlap(a, {0.2, 0.0, -0.7, 0, 0, 0}), 1.0, 1e-12) << "one above the other";
    // The same pair low down (0.3 m): narrow jets, no overlap to speak of.
    EXPECT_LT(jet_overlap({0, 0, -0.3, 0, 0, 0}, {0, 0.5, -0.3, 0, 0, 0}), 1e-3);
    // In a set, each neighbour carries its largest overlap with the others.
    const std::vector<RelState> set{a, b, {3, 3, -1.2, 0, 0, 0}};
    EXPECT_EQ(features_of(set, 0)[kOverlapFeature], jet_overlap(a, b));
    EXPECT_LT(features_of(set, 2)[kOverlapFeature], 1e-12);
    Bodies bodies;
    bodies.sufferer_kg = 0.067, bodies.neighbour_kg = {0.032, 0.067, 0.032};
    for (std::size_t i = 0; i < kOverlapFeature; ++i)
        EXPECT_EQ(features_of(set, 1, bodies)[i], features_of(b, 0.067, 0.067)[i]);
}

TEST(PredictorModel, DeepSetsIsItsBaselineWhereNoJetsOverlap) {
    LearntModel sum = random_model(Structure::sum, 7);
    LearntModel deep = random_model(Structure::deep_sets, 8);  // a residual that is not zero
    deep.input_mean = sum.input_mean, deep.input_std = sum.input_std, deep.output_scale = sum.output_scale;
    deep.baseline = sum.phi;
    auto same = [&](const std::vector<RelState>& x) {
        const auto a = deep.predict(x), b = sum.predict(x);
        for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(a[i], b[i], 1e-6 * (1 + std::abs(b[i]))) << i;
    };
    same({{0.1, 0.5, -1.2, 0, 0.5, 0}});                                // one neighbour
    same({{0.0, -3.0, -0.3, 0, 0.5, 0}, {0.0, 3.0, -0.3, 0, 0.5, 0}});  // two far apart
    const std::vector<RelState> stacked{{0.0, 0.0, -0.8, 0, 0.5, 0}, {0.0, 0.05, -1.3, 0, 0.5, 0}};
    EXPECT_GT(std::abs(deep.predict(stacked)[2] - sum.predict(stacked)[2]), 1e-4) << "overlapping jets: its own term";
    // Its sum part (what the regime map compares it with) is Σ psi, overlapping jets or not.
    const auto part = deep.sum_part().predict(stacked), base = sum.predict(stacked);
    for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(part[i], base[i], 1e-6 * (1 + std::abs(base[i]))) << i;
    // Without a baseline Deep Sets is the whole model: Phi(Σ phi), a lone neighbour included.
    deep.baseline = {};
    const std::vector<RelState> one{{0.1, 0.5, -1.2, 0, 0.5, 0}};
    EXPECT_GT(std::abs(deep.predict(one)[2]), 1e-4);
}

TEST(PredictorModel, DeepSetsOnABaselineStartsAsTheBaselineAndSavesIt) {
    dw::test::TempDir dir;
    LearntModel sum = random_model(Structure::sum, 5);
    LearntModel deep = random_model(Structure::deep_sets, 6);
    deep.input_mean = sum.input_mean, deep.input_std = sum.input_std, deep.output_scale = sum.output_scale;
    deep.baseline = sum.phi;
    deep.rho.layers.back().w.setZero();  // the residual's last layer at zero, as training starts it
    deep.rho.layers.back().b.setZero();
    const std::vector<RelState> x{{0.1, 0.5, -1.2, 0, 0.5, 0}, {0.0, -0.5, -1.3, 0, 0.5, 0}};
    const auto a = deep.predict(x), b = sum.predict(x);
    for (std::size_t i = 0; i < 6; ++i) EXPECT_NEAR(a[i], b[i], 1e-6 * (1 + std::abs(b[i])));
    deep.rho = random_model(Structure::deep_sets, 6).rho;  // a residual that is not zero
    deep.save(dir.file("d.json"));
    const LearntModel back = LearntModel::load(dir.file("d.json"));
    ASSERT_EQ(back.baseline.layers.size(), sum.phi.layers.size());
    const auto c = deep.predict(x), d = back.predict(x);
    for (std::size_t i = 0; i < 6; ++i) EXPECT_FLOAT_EQ(static_cast<float>(c[i]), static_cast<float>(d[i]));
}

// Trainings averaged into one model predict exactly the mean of their predictions, for either
// structure and for Deep Sets on a baseline (whose Phi(0) and psi average too); the result saves and
// loads as any model; members of different shapes or normalisations are refused with a line.
TEST(PredictorModel, AveragedMembersPredictTheMeanOfTheirPredictions) {
    dw::test::TempDir dir;
    const std::vector<RelState> x{{0.1, 0.05, -1.2, 0, 0.5, 0}, {0.0, -0.05, -0.8, 0, 0.5, 0}};
    for (int variant = 0; variant < 3; ++variant) {
        std::vector<LearntModel> members;
        for (unsigned seed = 11; seed < 14; ++seed) {
            LearntModel m = random_model(variant == 0 ? Structure::sum : Structure::deep_sets, seed);
            if (variant == 2) m.baseline = random_model(Structure::sum, seed + 100).phi;  // on a baseline
            members.push_back(m);
        }
        const LearntModel avg = average_of(members);
        EXPECT_EQ(avg.phi.layers[1].w.rows(), 3 * members[0].phi.layers[1].w.rows());
        avg.save(dir.file("avg.json"));
        const LearntModel back = LearntModel::load(dir.file("avg.json"));
        for (const auto& set : {std::vector<RelState>{x[0]}, x}) {
            Wrench6 mean{};
            for (const auto& m : members)
                for (std::size_t i = 0; i < 6; ++i) mean[i] += m.predict(set)[i] / 3;
            const auto a = avg.predict(set), b = back.predict(set);
            for (std::size_t i = 0; i < 6; ++i) {
                EXPECT_NEAR(a[i], mean[i], 1e-5 * (1 + std::abs(mean[i]))) << "variant " << variant << " axis " << i;
                EXPECT_FLOAT_EQ(static_cast<float>(a[i]), static_cast<float>(b[i]));
            }
            EXPECT_GT(std::abs(members[0].predict(set)[2] - mean[2]), 1e-4) << "the members differ";
        }
    }
    std::vector<LearntModel> mixed{random_model(Structure::sum, 1), random_model(Structure::deep_sets, 2)};
    EXPECT_THROW(average_of(mixed), dw::InputError);
    EXPECT_THROW(average_of(std::span<const LearntModel>{}), dw::InputError);
}

// Samples from a field that is a sum of single-neighbour jets plus a pair term the sum cannot hold.
Dataset synthetic(int legs, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    std::normal_distribution<double> noise(0, 0.02);
    Dataset d;
    d.sources.push_back({});
    for (int leg = 0; leg < legs; ++leg)
        for (int i = 0; i < 200; ++i) {
            Sample s;
            s.k = 2;
            s.leg = leg;
            double total = 0;
            for (std::size_t j = 0; j < 2; ++j) {
                s.x[j] = {u(rng), u(rng), -1.0 + 0.3 * u(rng), 0, 0.5, 0};
                total += std::exp(-(s.x[j][0] * s.x[j][0] + s.x[j][1] * s.x[j][1]) / 0.1);
            }
            s.y[2] = total + 0.5 * total * total + noise(rng);  // the square: jets that merge
            d.samples.push_back(s);
        }
    return d;
}

TEST(PredictorTraining, DeepSetsOnTheSumModelIsNeverWorseOnValidationAndLearnsThePairTerm) {
    const Split s = split_by_leg(synthetic(20, 3));
    TrainOptions o;
    o.kind = "learnt_linear";
    o.max_epochs = 15;
    const TrainResult sum = train_model(s.train, s.validation, o);
    // Every body here has one mass (the source's defaults): the masses did not vary, and weigh nothing.
    EXPECT_EQ(sum.model.input_std[kSuffererMassFeature], kUnvariedStd);
    EXPECT_GT(sum.model.input_std[0], 0.1F) << "a feature that varied keeps its spread";
    o.kind = "deep_sets";
    o.max_epochs = 40;  // the pair term is weighed by the two jets' overlap: it takes longer to learn
    const TrainResult deep = train_model(s.train, s.validation, o, &sum.model);
    EXPECT_LT(deep.best_validation_loss, 0.8 * sum.best_validation_loss) << "the residual learns what the sum cannot";
    EXPECT_EQ(deep.model.input_mean, sum.model.input_mean);  // the baseline's normalisation
    // Its psi trained on from the baseline's weights: it carries its own, not the sum model's.
    ASSERT_EQ(deep.model.baseline.layers.size(), sum.model.phi.layers.size());
    EXPECT_FALSE(deep.model.baseline.layers.front().w.isApprox(sum.model.phi.layers.front().w, 1e-4F));
    // The served model (Eigen) is the trained one (libtorch): the same validation error.
    double se = 0;
    for (const auto& v : s.validation.samples) {
        const auto p = deep.model.predict(v.neighbours());
        for (std::size_t a = 0; a < 6; ++a) se += std::pow((p[a] - v.y[a]) / deep.model.output_scale[a], 2);
    }
    EXPECT_NEAR(se / (6.0 * static_cast<double>(s.validation.samples.size())), deep.best_validation_loss,
                1e-3 * deep.best_validation_loss);
    // On its validation legs the result is never worse than the baseline it started from.
    o.max_epochs = 1;
    const TrainResult one = train_model(s.train, s.validation, o, &sum.model);
    EXPECT_LE(one.best_validation_loss, sum.best_validation_loss * (1 + 1e-4));
    o.kind = "learnt_linear";
    EXPECT_THROW(train_model(s.train, s.validation, o, &sum.model), dw::InputError) << "a baseline under a sum model";
}

TEST(PredictorModel, BadModelFilesNameTheField) {
    dw::test::TempDir dir;
    random_model(Structure::deep_sets, 3).save(dir.file("ok.json"));
    std::string text = dw::read_file(dir.file("ok.json"));
    auto expect_error = [&](const std::string& body, const std::string& needle) {
        std::ofstream(dir.file("bad.json")) << body;
        try {
            LearntModel::load(dir.file("bad.json"));
            FAIL() << "accepted: " << needle;
        } catch (const dw::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(needle), std::string::npos) << e.what();
        }
    };
    expect_error("{", "bad.json:1:1: not valid JSON");
    expect_error(R"({"format": "something/1"})", "format");
    auto unknown_kind = nlohmann::json::parse(text);  // issue 43: was accepted
    unknown_kind["kind"] = "crystal_ball";
    expect_error(unknown_kind.dump(),
                 "unknown model kind 'crystal_ball' (expected naive_linear, learnt_linear or deep_sets)");
    auto broken = nlohmann::json::parse(text);
    broken["structure"] = "ring";
    expect_error(broken.dump(), "structure");
    auto no_rho = nlohmann::json::parse(text);
    no_rho.erase("rho");
    expect_error(no_rho.dump(), "rho");
    auto wrong = nlohmann::json::parse(text);
    wrong["input"]["std"][2] = 0;
    expect_error(wrong.dump(), "input.std[2]");
    wrong = nlohmann::json::parse(text);
    wrong["phi"][1]["weight"][0].erase(0);
    expect_error(wrong.dump(), "phi[1].weight[1]: rows differ in length");
    wrong = nlohmann::json::parse(text);
    wrong["rho"][0]["weight"][3][2] = "x";
    expect_error(wrong.dump(), "rho[0].weight[3][2]: expected a number");
    // Issue 17: read by the one configuration layer: a misspelt key is refused, not ignored (a
    // Deep Sets model whose "baseline" were misspelt would have lost its baseline silently).
    wrong = nlohmann::json::parse(text);
    wrong["baselin"] = wrong["baseline"];
    wrong.erase("baseline");
    expect_error(wrong.dump(), "baselin: unknown key 'baselin'");
    wrong = nlohmann::json::parse(text);
    wrong["input"]["features"][0] = "north";
    expect_error(wrong.dump(), "input.features: expected dn, de, dd");
}

// A model that returns a known field: f_d = A exp(-|x - c|^2 / 2 s^2) of the first neighbour.
class GaussianModel final : public ForceModel {
public:
    GaussianModel(double n, double e, double amplitude) : n_(n), e_(e), a_(amplitude) {}
    const std::string& name() const override { return name_; }
    Wrench6 predict(std::span<const RelState> x) const override {
        if (x.empty()) return {};
        const double r2 = (x[0][0] - n_) * (x[0][0] - n_) + (x[0][1] - e_) * (x[0][1] - e_);
        return {0, 0, a_ * std::exp(-r2 / (2 * 0.15 * 0.15)), 0, 0, 0};
    }

private:
    std::string name_ = "gaussian";
    double n_, e_, a_;
};

TEST(PredictorMaps, ASyntheticFieldDrawsItsPeakWhereItIsOnTheRightScale) {
    dw::test::TempDir dir;
    // Peaks on grid nodes (-1.2 + 0.04 i), so the fields' extremes are exactly ±2 and -1.
    const GaussianModel g(0.48, -0.32, 2.0), h(-0.6, 0.68, -1.0);
    MapRequest r;
    r.formation = "single";
    r.speed_mps = 0;
    const auto png = dir.file("map.png");
    const MapLayout L = draw_force_map({&g, &h}, r, png);
    EXPECT_DOUBLE_EQ(L.vmax, 2.0);  // one symmetric scale over both panels: the larger |peak|
    EXPECT_DOUBLE_EQ(L.vmin, -2.0);
    const cv::Mat img = cv::imread(png);
    ASSERT_FALSE(img.empty());
    EXPECT_EQ(img.cols, L.width);
    // Panel 0: the reddest pixel is the peak; panel 1: the bluest is the trough.
    auto extreme = [&](int panel, bool red) {
        const auto& p = L.panels[static_cast<std::size_t>(panel)];
        auto score = [&](int x, int y) {
            const auto c = img.at<cv::Vec3b>(y, x);
            return red ? c[2] - c[1] : c[0] - c[2];
        };
        int best = -1000;
        for (int y = p.y; y < p.y + p.size; ++y)
            for (int x = p.x; x < p.x + p.size; ++x) best = std::max(best, score(x, y));
        double sx = 0, sy = 0, n = 0;  // the centre of the pixels of the extreme colour
        for (int y = p.y; y < p.y + p.size; ++y)
            for (int x = p.x; x < p.x + p.size; ++x)
                if (score(x, y) == best) sx += x, sy += y, n += 1;
        return std::array<int, 2>{static_cast<int>(std::lround(sx / n)), static_cast<int>(std::lround(sy / n))};
    };
    const auto peak = extreme(0, true), want = L.pixel(0, 0.48, -0.32);
    EXPECT_LE(std::abs(peak[0] - want[0]), 4);
    EXPECT_LE(std::abs(peak[1] - want[1]), 4);
    const auto trough = extreme(1, false), want1 = L.pixel(1, -0.6, 0.68);
    EXPECT_LE(std::abs(trough[0] - want1[0]), 4);
    EXPECT_LE(std::abs(trough[1] - want1[1]), 4);
    // The peak's colour is the scale's top colour; the trough (-1 of ±2) is half-way to blue.
    const auto top = colour_of(2.0, L.vmin, L.vmax), mid = colour_of(-1.0, L.vmin, L.vmax);
    const auto cp = img.at<cv::Vec3b>(peak[1], peak[0]), ct = img.at<cv::Vec3b>(trough[1], trough[0]);
    for (int c = 0; c < 3; ++c) {
        EXPECT_NEAR(cp[c], top[static_cast<std::size_t>(c)], 12);
        EXPECT_NEAR(ct[c], mid[static_cast<std::size_t>(c)], 12);
    }
}

// f_d as a function of the neighbours: known fields for the regime rule.
class FieldModel final : public ForceModel {
public:
    FieldModel(std::string name, std::function<double(std::span<const RelState>)> f)
        : name_(std::move(name)), f_(std::move(f)) {}
    const std::string& name() const override { return name_; }
    Wrench6 predict(std::span<const RelState> x) const override { return {0, 0, f_(x), 0, 0, 0}; }

private:
    std::string name_;
    std::function<double(std::span<const RelState>)> f_;
};

double jet(const RelState& x) { return std::exp(-(x[0] * x[0] + x[1] * x[1]) / 0.05); }
double jets(std::span<const RelState> x) {
    double s = 0;
    for (const auto& n : x) s += jet(n);
    return s;
}

// Legs along E at 1.3 m: k neighbours 0.3 m apart, f_d = truth(neighbours) + noise.
Dataset legs_of(int k, const std::function<double(std::span<const RelState>)>& truth, double noise_n) {
    std::mt19937 rng(11);
    std::normal_distribution<double> noise(0, noise_n);
    Dataset d;
    d.sources.push_back({});
    d.sources[0].formation = k == 1 ? "single K=1" : "pair K=2";
    for (int leg = 0; leg < 8; ++leg)
        for (int i = 0; i < 320; ++i) {  // 4 s at 80 Hz, -1 .. 1 m
            Sample s;
            s.k = k, s.leg = leg, s.t = leg * 10.0 + i / 80.0;
            const double e = -1 + i / 160.0, n = -0.35 + 0.1 * leg;
            for (int j = 0; j < k; ++j) s.x[static_cast<std::size_t>(j)] = {n, e + 0.3 * j, -1.3, 0, 0.5, 0};
            s.y[2] = truth(s.neighbours()) + noise(rng);
            d.samples.push_back(s);
        }
    return d;
}

TEST(PredictorRegimes, TheRuleSeparatesNoiseSumsAndMergingJets) {
    const FieldModel sum("sum", jets);
    auto merged = [](std::span<const RelState> x) {
        return jets(x) + 0.8 * jets(x) * jets(x);
    };  // the square: jets that merge
    const FieldModel deep("deep", merged);
    auto regime = [](const Dataset& d, const ForceModel& s, const ForceModel& m) {
        const auto rows = classify_regimes(s, m, d, {1.3});
        EXPECT_EQ(rows.size(), 1u);
        return rows.empty() ? RegimeRow{} : rows.front();
    };
    // Merging jets, and Deep Sets knows it: non-linear, with its gain measured.
    const RegimeRow r = regime(legs_of(2, merged, 0.02), sum, deep);
    EXPECT_EQ(r.regime, Regime::non_linear) << r.z << " " << r.gain;
    EXPECT_GT(r.gain, 0.5);
    EXPECT_EQ(r.legs, 8u);
    // A plain sum: Deep Sets has nothing to add.
    EXPECT_EQ(regime(legs_of(2, jets, 0.02), sum, FieldModel("deep", jets)).regime, Regime::linear);
    // Noise and nothing else, which neither model explains: chaotic.
    const RegimeRow c = regime(legs_of(
                                   2, [](auto) { return 0.0; }, 0.3),
                               sum, deep);
    EXPECT_EQ(c.regime, Regime::chaotic) << c.explained;
    EXPECT_NEAR(c.signal_rms, 0.3, 0.02);
    // One neighbour has no aggregate: never non-linear, however much better the second model is.
    EXPECT_EQ(regime(legs_of(1, merged, 0.02), sum, deep).regime, Regime::linear);
}

TEST(PredictorMetric, ArenaErrorIsTheMeanCellDifference) {
    // Samples on two cells at 1.3 m; truth 1 N; a model predicting 1.5 N errs 0.5 everywhere.
    Dataset d;
    d.sources.push_back({"x", "single K=1"});
    for (int i = 0; i < 100; ++i) {
        Sample s;
        s.k = 1;
        s.x[0] = {0.05, i < 50 ? 0.05 : 0.55, -1.3, 0, 0.5, 0};
        s.y = {0, 0, 1.0 + (i % 2 ? 0.1 : -0.1), 0, 0, 0};  // noise averages out per cell
        s.leg = 0;
        d.samples.push_back(s);
    }
    class Const final : public ForceModel {
    public:
        const std::string& name() const override { return n; }
        Wrench6 predict(std::span<const RelState>) const override { return {0, 0, 1.5, 0, 0, 0}; }
        std::string n = "const";
    } m;
    const auto e = arena_error(m, d);
    EXPECT_NEAR(e[2], 0.5, 1e-12);
    EXPECT_NEAR(e[0], 0.0, 1e-12);
    // The integral: 0.5 N over two occupied 0.1 m cells = 0.01 N·m².
    EXPECT_NEAR(arena_integral(m, d)[2], 0.5 * 2 * 0.01, 1e-12);
    ArenaOptions far;
    far.altitude_m = 0.3;
    EXPECT_TRUE(std::isnan(arena_error(m, d, far)[2]));
    EXPECT_TRUE(std::isnan(arena_integral(m, d, far)[2]));
    EXPECT_TRUE(d.in_altitude_band(0.3, 0.15).samples.empty());
    EXPECT_EQ(d.in_altitude_band(1.3, 0.15).samples.size(), d.samples.size());
}

// The issue's claims, on simulated flights with fixed seeds (the table: dw-predictor study).
// Deep Sets' D RMSE / the physics floor with jet merging: the issue's target (at this seed Leader
// Follower K=3 is at 1.49, docs/PREDICTOR.md).
constexpr double kMergingFloorTarget = 1.5;
// The size the two studies run at. The accuracy claims hold at the study's own size (90 legs a
// flight, 150 epochs): at 45 legs Deep Sets is up to 3.6 x the physics floor (issue 40,
// docs/PREDICTOR.md), so the default run checks what the study makes — every table, band, regime
// and picture — on small flights, and --full checks the accuracy too.
struct StudySize {
    int legs, max_epochs;
    bool accuracy;
    int jobs;  // the small study flies and trains one at a time: one thread's slots beside the real-time tests
};
constexpr StudySize kSmallStudy{18, 10, false, 1};
const StudySize kFullStudy{StudyOptions{}.legs, StudyOptions{}.max_epochs, true, StudyOptions{}.jobs};

// Where jets merge, Deep Sets beats the sum; where the physics is a sum, nothing invents nonlinearity.
static void study_accuracy(const StudyResult& merging, const StudyResult& sum) {
    const double lin = table_value(merging.table, "leader_follower K=3", "learnt_linear", 2);
    const double deep = table_value(merging.table, "leader_follower K=3", "deep_sets", 2);
    EXPECT_LE(deep, 0.7 * lin) << "jet merging: Deep Sets " << deep << " vs learnt linear " << lin;
    // Where jets merge, Deep Sets is closer than the sum it is built on; with one neighbour too: its
    // psi, trained on beside the residual, is no longer bent by the merged flights.
    for (const auto& row : merging.table)
        if (row.model == "deep_sets") {
            EXPECT_LT(row.rmse[2], table_value(merging.table, row.formation, "learnt_linear", 2, false))
                << row.formation;
            EXPECT_LE(row.rmse[2], kMergingFloorTarget * table_value(merging.table, row.formation, "physics", 2, false))
                << row.formation << ": Deep Sets vs the physics floor";
        }
    for (const auto& row : sum.table) {
        if (row.model != "deep_sets") continue;
        SCOPED_TRACE(row.formation);
        // Where the physics is a sum, every learnt model reaches the physics floor (RMSE, D) and the
        // sum model is as good as Deep Sets: the lab does not invent nonlinearity.
        const double floor = table_value(sum.table, row.formation, "physics", 2, false);
        EXPECT_LE(row.rmse[2], 1.5 * floor) << "Deep Sets vs the physics floor";
        EXPECT_LE(table_value(sum.table, row.formation, "learnt_linear", 2, false), 1.5 * floor)
            << "learnt linear vs the floor";
        EXPECT_LE(table_value(sum.table, row.formation, "learnt_linear", 2), 1.1 * row.arena[2])
            << "learnt linear vs Deep Sets";
    }
    // In every formation and altitude band of either study, Deep Sets is not worse than learnt linear by more than 10 %.
    for (const auto* study : {&merging, &sum})
        for (const auto& [altitude, rows] : study->by_altitude)
            for (const auto& row : rows)
                if (row.model == "deep_sets")
                    EXPECT_LE(row.arena[2], 1.1 * table_value(rows, row.formation, "learnt_linear", 2))
                        << row.formation << " at " << altitude << " m";
    // The regime map (Deep Sets against its own sum part): merging jets high up are non-linear;
    // low down, where jets do not merge, and where the physics is a sum, nothing is.
    auto regime_of = [](const StudyResult& r, const std::string& formation, double altitude) {
        for (const auto& row : r.regimes)
            if (row.formation == formation && std::abs(row.altitude_m - altitude) < 1e-9) return row.regime;
        ADD_FAILURE() << formation << " at " << altitude << " m has no regime";
        return Regime::chaotic;
    };
    EXPECT_EQ(regime_of(merging, "leader_follower K=3", 1.3), Regime::non_linear);
    EXPECT_EQ(regime_of(merging, "leader_follower K=3", 0.3), Regime::linear);
    for (const auto& row : sum.regimes)
        EXPECT_NE(row.regime, Regime::non_linear) << row.formation << " at " << row.altitude_m << " m";
}

static void study_claims(const StudySize& size) {
    dw::test::TempDir dir;
    StudyOptions o;
    o.legs = size.legs;
    o.max_epochs = size.max_epochs;
    o.jobs = size.jobs;
    o.generalisation = false;
    o.maps = false;
    o.out_dir = dir.file("merging");
    dw::physics::effect_type("jet_merging").switch_on(o.physics.effects);
    const auto merging = run_study(o);
    o.out_dir = dir.file("sum");
    dw::physics::effect_type("jet_merging").clear(o.physics.effects);
    const auto sum = run_study(o);
    if (size.accuracy) study_accuracy(merging, sum);
    EXPECT_TRUE(std::filesystem::exists(sum.markdown_path));
    EXPECT_EQ(sum.regimes.size(), 18u);  // six formations at three altitudes
    EXPECT_TRUE(std::filesystem::exists(dir.file("sum/regimes.png")));
    // Every altitude band the flights fly has its own table, with the arena metric at that band.
    ASSERT_EQ(sum.by_altitude.size(), 3u);
    for (const auto& [altitude, rows] : sum.by_altitude) {
        SCOPED_TRACE(altitude);
        const double v = table_value(rows, "leader_follower K=3", "deep_sets", 2);
        EXPECT_TRUE(std::isfinite(v) && v > 0);
        for (const auto& row : rows)  // a stand measures every axis: every RMSE is a number
            for (std::size_t a = 0; a < 6; ++a)
                EXPECT_TRUE(std::isfinite(row.rmse[a])) << row.formation << " " << row.model << " axis " << a;
    }
    const std::string md = dw::read_file(sum.markdown_path, "table");
    for (const char* h : {"### 0.3 m", "### 0.8 m", "### 1.3 m", "integrated over the occupied cells"})
        EXPECT_NE(md.find(h), std::string::npos) << h;
}
TEST(PredictorStudy, MakesEveryTableBandAndRegimeOnSmallFlights) { study_claims(kSmallStudy); }
TEST(PredictorStudyFull, DeepSetsBeatsLinearOnlyWhereJetsMerge) { study_claims(kFullStudy); }

// Issue 71, item 5: `dw-predictor compare` on every file a `real` run writes (models/*.json and
// models/physics.yaml). A correction (<kind>_on_physics.json) was scored as a model on its own, and
// two files of one kind gave a table whose header listed fewer names than each cell had values; the
// reference row was dropped whenever one flight lacked reference.csv. Now: a correction is served
// composed with the physics it carries, one saved without it is refused in one line, every name
// is distinct and every cell has one value per name, and the reference row is shown over the
// flights that carry one, the others named.
TEST(PredictorCompare, EveryFileOfARealRunIsComparedAsAUserRunsIt) {
    dw::test::TempDir dir;
    const auto with_reference = small_flight(dir, "leader_follower", 10);
    const auto without = small_flight(dir, "side_by_side", 10);
    {  // the first flight carries a recorded prediction of f_d: the wrench's, halved
        auto f = dw::flight::read_flight(with_reference);
        f.meta.reference = dw::flight::ReferenceInfo{"half the truth (a test's)", {"f_d"}};
        for (const auto& w : f.wrench) f.reference.push_back({w.t, {NAN, NAN, w.w[2] / 2, NAN, NAN, NAN}});
        std::filesystem::remove_all(with_reference);
        dw::flight::write_flight(f, with_reference);
    }
    std::filesystem::create_directories(dir.file("models"));
    const dw::physics::PhysicsConfig physics;
    dw::write_file(dir.file("models/physics.yaml"), dw::physics::to_yaml(physics));
    random_model(Structure::sum, 1).save(dir.file("models/learnt_linear.json"));
    random_model(Structure::deep_sets, 2).save(dir.file("models/deep_sets.json"));
    LearntModel correction = random_model(Structure::sum, 3);
    mark_correction(correction, physics);
    correction.save(dir.file("models/learnt_linear_on_physics.json"));
    // Served composed: the physics' prediction plus the correction's.
    const auto composed = load_model(dir.file("models/learnt_linear_on_physics.json"));
    EXPECT_EQ(composed->name(), "physics+learnt_linear");
    const std::array<RelState, 1> x{RelState{0.1, 0.0, -0.6, 0, 0, 0}};
    const auto sum = PhysicsModel(physics).predict(x), alone = correction.predict(x), both = composed->predict(x);
    for (std::size_t a = 0; a < 6; ++a) EXPECT_NEAR(both[a], sum[a] + alone[a], 1e-9) << a;
    // A correction saved without its physics (before this change) is no model: one line, exit 2.
    random_model(Structure::deep_sets, 4).save(dir.file("models/deep_sets_on_physics.json"));
    const auto old = dw::test::run(
        {dw::test::bin("dw-predictor"), "compare", "--models", dir.file("models/deep_sets_on_physics.json"), "--data",
         with_reference, "--out", dir.file("old")},
        dir);
    dw::test::expect_one_line_exit_2(old, "does not carry the physics it corrects");
    // The run's files, and the same learnt_linear twice (another run's).
    std::filesystem::create_directories(dir.file("other"));
    std::filesystem::copy_file(dir.file("models/learnt_linear.json"), dir.file("other/learnt_linear.json"));
    const auto r =
        dw::test::run({dw::test::bin("dw-predictor"), "compare", "--models", dir.file("models/physics.yaml"),
                       dir.file("models/learnt_linear.json"), dir.file("models/deep_sets.json"),
                       dir.file("models/learnt_linear_on_physics.json"), dir.file("other/learnt_linear.json"), "--data",
                       with_reference, without, "--out", dir.file("cmp")},
                      dir);
    ASSERT_EQ(r.status, 0) << r.err;
    const std::string md = dw::read_file(dir.file("cmp/table.md"));
    const std::vector<std::string> names{"physics",
                                         "learnt_linear (" + dir.file("models/learnt_linear.json") + ")",
                                         "deep_sets",
                                         "physics+learnt_linear",
                                         "learnt_linear (" + dir.file("other/learnt_linear.json") + ")",
                                         "reference (1 of 2 flights)"};
    EXPECT_NE(md.find("Each cell: " + dw::log::join(names, " / ") + "."), std::string::npos) << md;
    EXPECT_NE(md.find("not over " + without + " ("), std::string::npos) << md;
    // Every cell of the RMSE table holds one value per name (– where the reference has no flight).
    const auto rmse = md.substr(md.find("### RMSE"));
    for (const auto& line : dw::test::lines(rmse.substr(0, rmse.find("### Peak")))) {
        if (line.rfind("| leader_follower", 0) != 0 && line.rfind("| side_by_side", 0) != 0) continue;
        const auto cells = line.substr(line.find('|', line.find('|', 1) + 1));  // past formation and samples
        const auto slashes = static_cast<std::size_t>(std::count(cells.begin(), cells.end(), '/'));
        EXPECT_EQ(slashes, 6 * (names.size() - 1)) << line;
    }
}

// Issue 71, item 4: the 95 % intervals' noise model. A flight's floor is its recorded spread where
// no jet reaches (nobody near, or the physics predicting no push); about a right prediction p the
// recording scatters with sd² = floor² + (2 I p)² (an uncalibrated physics' noise model), so
// an exact model's intervals hold 95 % of the samples and a biased one's far fewer.
TEST(PredictorIntervals, AnExactModelsIntervalsHoldNinetyFivePercent) {
    struct Constant final : ForceModel {  // f_d: `near_n` with a neighbour within 0.3 m, else 0
        double near_n = 0;
        std::string label = "constant";
        const std::string& name() const override { return label; }
        Wrench6 predict(std::span<const RelState> x) const override {
            Wrench6 w{};
            w[kFdAxis] = !x.empty() && std::hypot(x[0][0], x[0][1]) <= 0.3 ? near_n : 0;
            return w;
        }
    };
    constexpr double kFloor = 0.01, kIntensity = 0.1, kPush = 0.2;
    Constant exact;
    exact.near_n = kPush;
    Dataset d;
    d.sources.push_back(Source{});
    d.sources.back().name = "synthetic";
    std::mt19937 rng(71);
    std::normal_distribution<double> unit(0, 1);
    for (int i = 0; i < 20000; ++i) {
        Sample s;
        s.k = 1;
        s.x[0] = RelState{i % 2 ? 3.0 : 0.1, 0, -0.5, 0, 0, 0};  // far, near, far, near, ...
        const double p = exact.predict(s.neighbours())[kFdAxis];
        s.y[kFdAxis] = p + unit(rng) * std::sqrt(kFloor * kFloor + 4 * kIntensity * kIntensity * p * p);
        d.samples.push_back(s);
    }
    // A second flight of the same sufferer where someone is always near: its floor is its class's.
    d.sources.push_back(Source{});
    d.sources.back().name = "always near";
    for (int i = 0; i < 100; ++i) {
        Sample s;
        s.k = 1;
        s.source = 1;
        s.x[0] = RelState{0.1, 0, -0.5, 0, 0, 0};
        s.y[kFdAxis] = kPush + unit(rng) * 0.05;
        d.samples.push_back(s);
    }
    // A third whose neighbour is always near but 0.5 m below, where the physics predicts no push
    // (under physics::kQuietPush_n): quiet, so its floor is its own. (Another vehicle: another class.)
    d.sources.push_back(Source{});
    d.sources.back().name = "neighbour below";
    d.sources.back().sufferer.mass_kg *= 2;
    for (int i = 0; i < 200; ++i) {
        Sample s;
        s.k = 1;
        s.source = 2;
        s.x[0] = RelState{0.1, 0, 0.5, 0, 0, 0};
        s.y[kFdAxis] = unit(rng) * 3 * kFloor;
        d.samples.push_back(s);
    }
    dw::physics::PhysicsConfig physics;
    physics.turbulence.intensity = kIntensity;
    const NoiseModel noise = noise_model(d, physics);
    EXPECT_NEAR(noise.floor.at("synthetic")[kFdAxis], kFloor, 0.05 * kFloor);
    EXPECT_NEAR(noise.floor.at("neighbour below")[kFdAxis], 3 * kFloor, 0.3 * kFloor);
    EXPECT_EQ(noise.floor.at("always near")[kFdAxis], noise.floor.at("synthetic")[kFdAxis]);
    EXPECT_EQ(noise.from_class, std::vector<std::string>{"always near"});
    EXPECT_TRUE(noise.from_differences.empty());
    // A calibrated class floor (the physics' vehicle class of that sufferer) comes first.
    auto calibrated = physics;
    calibrated.classes.push_back({"the sufferer's", d.sources[1].sufferer, {}, 1.18, 0.1, 0.02});
    EXPECT_EQ(noise_model(d, calibrated).floor.at("always near")[kFdAxis], 0.02);
    d.samples.resize(20000);  // the first flight alone, below
    EXPECT_NEAR(coverage(exact, d, noise), 0.95, 0.01);
    Constant biased;  // 3 sd short where the jet pushes: most of those samples fall outside (about 0.63 in all)
    biased.near_n = kPush - 3 * std::sqrt(kFloor * kFloor + 4 * kIntensity * kIntensity * kPush * kPush);
    EXPECT_LT(coverage(biased, d, noise), 0.7);
    // Without the turbulence term the near samples' spread is not the floor's: too few inside (about 0.79).
    physics.turbulence.enabled = false;
    EXPECT_LT(coverage(exact, d, noise_model(d, physics)), 0.85);
}
