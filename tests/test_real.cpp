// Real flights (issue 15): the physics per body and a flying sufferer (synthetic flights, always
// run), and the explainer and the predictor on every shared Neural-Swarm trial (read from
// ../shared in place; skipped with the reason when absent).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <random>
#include <nlohmann/json.hpp>

#include "analysis/explain.hpp"
#include "analysis/proof.hpp"
#include "analysis/session.hpp"
#include "analysis/session_proof.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "analysis/calibrate.hpp"
#include "importer/neural_swarm.hpp"
#include "physics/bodies.hpp"
#include "predictor/real.hpp"
#include "real_data.hpp"
#include "support.hpp"

namespace fs = std::filesystem;
using dw::flight::Flight;

namespace {

// A flying sufferer at 1 m crossing under a neighbour hovering at 1.5 m, along E, `passes` times
// in 20 s (e = cos(pi passes t / 20): under it at t = (k + 1/2) 20 / passes); the wrench is all zeros at 50 Hz.
Flight crossing(int passes, double neighbour_mass_kg = 0.7) {
    Flight f;
    f.meta.sufferer = "s";
    f.meta.neighbours = {"n"};
    f.meta.stand_height_m.reset();
    f.meta.wrench_source = dw::flight::WrenchSource::residual;
    f.meta.moments_measured = false;
    f.meta.vehicles["n"] = {neighbour_mass_kg, 4, 0.0635, 0.25};
    f.meta.vehicles["s"] = {0.7, 4, 0.0635, 0.25};
    const auto s = f.body_index("s"), n = f.body_index("n");
    for (int i = 0; i <= 2000; ++i) {
        const double t = i * 0.01;
        f.poses.push_back({t, s, {0, std::cos(M_PI * passes * t / 20.0), -1.0}, {1, 0, 0, 0}});
        f.poses.push_back({t, n, {0, 0, -1.5}, {1, 0, 0, 0}});
        if (i % 2 == 0) f.wrench.push_back({t, {}});
    }
    return f;
}

// The time and value of the largest simulated f_d at the wrench stamps.
std::pair<double, double> peak_f_d(const Flight& f, const dw::physics::PhysicsConfig& c = {}) {
    const dw::analysis::Resimulation r(f, c);
    const auto w = r.recorded(c);
    std::size_t best = 0;
    for (std::size_t i = 0; i < w.size(); ++i)
        if (w[i][2] > w[best][2]) best = i;
    return {r.stamps()[best], w[best][2]};
}

}  // namespace

TEST(RealPhysics, AFlyingSuffererFeelsTheJetWhereItsRecordedPoseIs) {
    const auto [t, f_d] = peak_f_d(crossing(1));
    EXPECT_NEAR(t, 10.0, 0.2);  // the sufferer under the neighbour: e = 0 at t = 10 s
    EXPECT_GT(f_d, 0.05);
}

TEST(RealPhysics, EachBodyTakesItsOwnParametersFromTheFlight) {
    const double small = peak_f_d(crossing(1, 0.35)).second, large = peak_f_d(crossing(1, 1.4)).second;
    EXPECT_GT(large, 1.5 * small);  // a heavier producer blows harder: not two identical vehicles
    // The physics configuration's own neighbour serves only a body the flight does not describe.
    auto undescribed = crossing(1, 1.4);
    undescribed.meta.vehicles.erase("n");
    dw::physics::PhysicsConfig c;
    c.neighbour.mass_kg = 0.35;
    EXPECT_NEAR(peak_f_d(undescribed, c).second, small, 1e-9);
    // The sufferer's own size too: bigger discs catch more of the jet.
    auto big_sufferer = crossing(1);
    big_sufferer.meta.vehicles["s"].prop_radius_m = 0.1;
    EXPECT_GT(peak_f_d(big_sufferer).second, 1.2 * peak_f_d(crossing(1)).second);
}

TEST(RealPhysics, UnusableBodyParametersAreOneClearError) {
    dw::physics::VehicleParams zero_disc;
    zero_disc.prop_radius_m = 0;
    dw::physics::PhysicsConfig c;
    c.neighbour = zero_disc;
    auto f = crossing(1);
    f.meta.vehicles.erase("n");  // so the configuration's (unusable) neighbour is used
    try {
        dw::analysis::Resimulation r(f, c);
        FAIL() << "a neighbour without a propeller disc was accepted";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("vehicles.n"), std::string::npos) << e.what();
    }
}

// The noise floor says what it is: where nobody is ever far (a swap), the spread of successive
// differences; where the flight has far samples, its own spread there (the report quotes which).
TEST(RealNoise, TheNoiseFloorSaysWhichSpreadItIs) {
    auto f = crossing(6);
    for (auto& p : f.poses) p.p[1] *= 0.05;  // the sufferer never leaves the neighbour's side
    for (auto& w : f.wrench) w.w[2] = 0.02 * std::sin(w.t) + 0.001 * std::sin(40 * w.t);  // slow, and jitter
    const dw::physics::PhysicsConfig c;
    const dw::analysis::Resimulation r(f, c);
    const auto near = dw::analysis::floor_of(r, dw::analysis::describe(r, dw::flight::find_blocks(f, 5, {0.3})),
                                             r.recorded(c), c.stand.tare_s);
    EXPECT_EQ(near.basis, dw::analysis::FloorBasis::differences);
    EXPECT_LT(near.sigma[2], 0.005);  // the jitter: the slow error is not in this floor
    auto walk = crossing(6);
    for (auto& p : walk.poses) p.p[1] *= 3;  // out to 3 m, beyond the near radius
    const dw::analysis::Resimulation rw(walk, c);
    const auto far = dw::analysis::floor_of(rw, dw::analysis::describe(rw, dw::flight::find_blocks(walk, 5, {0.3})),
                                            rw.recorded(c), c.stand.tare_s);
    EXPECT_EQ(far.basis, dw::analysis::FloorBasis::far_samples);
}

TEST(RealBlocks, FlightsWithoutLegsAreSplitByEncounterElseByTime) {
    const std::vector<double> radius{0.3};
    const auto six = dw::flight::find_blocks(crossing(6), 5, radius);
    EXPECT_EQ(six.kind, dw::flight::BlockKind::encounters);
    ASSERT_EQ(six.blocks.size(), 6u);
    EXPECT_DOUBLE_EQ(six.blocks.front().t_start, 0.0);
    EXPECT_DOUBLE_EQ(six.blocks.back().t_end, 20.0);
    for (std::size_t k = 1; k < six.blocks.size(); ++k)
        EXPECT_DOUBLE_EQ(six.blocks[k].t_start, six.blocks[k - 1].t_end);
    const auto one = dw::flight::find_blocks(crossing(1), 5, radius);
    EXPECT_EQ(one.kind, dw::flight::BlockKind::time);
    EXPECT_GE(one.blocks.size(), 10u);
}

TEST(RealBlocks, TheFlightViewIsTheSuffererAndItsNeighboursWalkedBlockByBlock) {
    const auto f = crossing(6);
    const auto bodies = dw::flight::body_tracks(f, "crossing/");
    ASSERT_EQ(bodies.neighbours.size(), 1u);
    EXPECT_EQ(bodies.sufferer.t.size() + bodies.neighbours[0].t.size(), f.poses.size());
    const auto blocks = dw::flight::find_blocks(f, 5, {0.3});
    dw::flight::BlockCursor cursor(blocks.blocks);
    for (const auto& b : blocks.blocks) {
        const double mid = 0.5 * (b.t_start + b.t_end);
        ASSERT_NE(cursor.at(mid), nullptr);
        EXPECT_EQ(cursor.at(mid)->leg, b.leg);
    }
    EXPECT_EQ(cursor.at(blocks.blocks.back().t_end + 1.0), nullptr);  // past the last block
    // A neighbour named in meta.json without poses is one clear error naming it and the flight.
    auto lost = f;
    lost.meta.neighbours.push_back("ghost");
    try {
        dw::flight::body_tracks(lost, "crossing/");
        FAIL() << "a neighbour without poses was accepted";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("crossing/poses.csv: the neighbour 'ghost'"), std::string::npos)
            << e.what();
    }
}

TEST(RealPredictor, NoHeldOutSampleIsOneLineNeverAnEmptyTable) {
    dw::test::TempDir d;
    auto f = crossing(6);
    for (auto& p : f.poses)
        if (p.body == 1) p.p = {0, 50, -1.5};  // the neighbour far away: no sample has a neighbour
    dw::flight::write_flight(f, d.file("far"));
    dw::predictor::RealOptions o;
    o.data = {d.file("far")};
    o.out_dir = d.file("out");
    try {
        dw::predictor::run_real(o);
        FAIL() << "an empty comparison was accepted";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no held-out samples"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(d.file("out/table.md")));
}

// ---- the shared real flights

namespace {

std::string import_trial(const dw::test::Trial& t, const dw::test::TempDir& d) {
    const auto f = dw::importer::neural_swarm_importer().import(t.paths(), {t.sufferer, {}, {}});
    const std::string dir = d.file(t.name);
    dw::flight::write_flight(f, dir);
    return dir;
}

}  // namespace

// The three tests below explain the shared flights with the published jet law (the hand-made,
// uncalibrated physics): what they assert — the law over-predicts these vehicles' downwash, the
// explainer finds that, the learnt models beat the physics, concealed effects are recovered on
// top — is about that physics. The calibrated one is tested in test_calibrate.cpp.
TEST(RealFlights, TheExplainerSaysWhatEachSharedFlightShows) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    dw::analysis::ExplainOptions o;
    o.physics = dw::physics::load_physics(dw::test::crazyflie_uncalibrated_physics());
    for (const auto& t : dw::test::shared_trials()) {
        SCOPED_TRACE(t.name);
        const auto f = dw::flight::read_flight(import_trial(t, d));
        const auto r = dw::analysis::explain(f, o);
        EXPECT_EQ(r.blocks, dw::flight::BlockKind::encounters);
        EXPECT_GE(r.legs, 5u);
        // Real downwash is in every trial and the mean-flow physics does not match it within noise.
        EXPECT_GT(r.heldout_before[2], 1.5 * r.noise_floor[2]);  // 1.6 to 8 times on these flights
        // The explainer says so (under the small vehicle's weaker wake on the large one no candidate
        // passes the held-out test: it is found by its excess over the noise) and, but for that
        // flight, where: there no cell reaches even |z| 3 (docs/REAL.md).
        EXPECT_TRUE(r.detected);
        if (t.name != "swap_sl_large_under_small") EXPECT_FALSE(r.regions.empty());
        for (std::size_t a = 3; a < 6; ++a) EXPECT_EQ(r.heldout_before[a], 0.0) << "moments are not measured";
        if (t.name.starts_with("swap") && t.name != "swap_sl_large_under_small") {
            // The crossings: an accepted effect removes at least a third of the held-out f_d error —
            // or (issue 68) the law's wrong shape is not stood in for by one: the flight is reported
            // unexplained and what is left is modelled by the learnt discrepancy.
            if (!r.accepted.empty()) EXPECT_LT(r.heldout_after[2], 0.67 * r.heldout_before[2]);
            else EXPECT_TRUE(r.unexplained && r.discrepancy.significant) << r.discrepancy.note;
        }
        // What the physics gets wrong about these small vehicles: it over-predicts their
        // downwash — fitted alone, the force scale is well below 1 wherever it was tried.
        for (const auto& c : r.candidates)
            if (c.effect.name == "force_scale" && c.round == 1 && t.name != "swap_sl_large_under_small")
                EXPECT_LT(c.values[0], 0.8);
        // Issue 71: no effect is accepted whose interval holds its neutral value where that value is
        // its absence (the rig's effects: a clock of 0, a scale of 1, no lag, no leak).
        for (const auto& a : r.accepted)
            if (dw::physics::of_the_rig(*a.effect.type))
                EXPECT_FALSE(a.effect.holds_neutral(a.lo, a.hi)) << a.effect.name << " " << a.note;
        const std::string out = d.file(t.name + "_report");
        dw::analysis::write_report(f, r, o, out);
        for (const char* file :
             {"report.json", "report.md", "physics.yaml", "residual_vs_position.png", "encounters.png"})
            EXPECT_TRUE(fs::exists(out + "/" + file)) << file;
        const auto j = nlohmann::json::parse(dw::read_file(out + "/report.json", "report"));
        EXPECT_EQ(j["cross_validation"]["blocks"], "encounters");
        EXPECT_EQ(j["format"], "downwash-explain/1");
        // A flying sufferer's report speaks of its force estimate, not of a stand or its legs.
        const std::string md = dw::read_file(out + "/report.md", "report");
        for (const char* stand_words : {"the stand's", "Recalibrate the stand", "on +E and −E legs.", "| −E |"})
            EXPECT_EQ(md.find(stand_words), std::string::npos) << stand_words;
    }
}

TEST(RealFlights, ThePredictorComparesEveryModelOnHeldOutEncounters) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    dw::predictor::RealOptions o;
    for (const auto& t : dw::test::shared_trials()) o.data.push_back(import_trial(t, d));
    o.physics = dw::physics::load_physics(dw::test::crazyflie_uncalibrated_physics());
    o.out_dir = d.file("real");
    o.max_epochs = 40;
    const auto r = dw::predictor::run_real(o);
    EXPECT_TRUE(r.naive);
    EXPECT_GT(r.test, 2000u);
    std::map<std::string, std::map<std::string, const dw::predictor::ComparisonRow*>> by;  // formation -> model
    for (const auto& row : r.table) by[row.formation][row.model] = &row;
    ASSERT_EQ(by.size(), 2u);  // the two-vehicle flights and the three-vehicle swap
    for (const auto& [formation, models] : by) {
        SCOPED_TRACE(formation);
        // physics, naive linear, learnt linear, Deep Sets, and the last two on the physics; and the
        // onboard network's prediction over the flights whose logs carry it (issue 71: it was
        // dropped whenever one flight lacked it), named with how many.
        std::size_t references = 0;
        for (const auto& [name, row] : models) references += name.rfind("reference", 0) == 0;
        ASSERT_EQ(models.size() - references, 6u);
        EXPECT_LE(references, 1u);
        for (const auto& [name, row] : models) {
            if (name.rfind("reference", 0) == 0) continue;
            EXPECT_TRUE(std::isfinite(row->rmse[2])) << name;
            EXPECT_TRUE(std::isfinite(row->peak_error)) << name;
            EXPECT_TRUE(row->coverage_f_d > 0 && row->coverage_f_d <= 1) << name << ": " << row->coverage_f_d;
            EXPECT_GE(row->blocks, 2u);
            EXPECT_TRUE(std::isnan(row->rmse[3])) << "moments are not measured";
        }
        // Learnt from the real data, the models beat the physics on the held-out encounters.
        EXPECT_LT(models.at("learnt_linear")->rmse[2], models.at("physics")->rmse[2]);
        EXPECT_LT(models.at("deep_sets")->rmse[2], models.at("physics")->rmse[2]);
    }
    EXPECT_TRUE(fs::exists(r.map_path));
    const auto md = dw::read_file(r.markdown_path, "table");
    EXPECT_NE(md.find("Peak f_d error"), std::string::npos);
    EXPECT_TRUE(md.find("No reference row") != std::string::npos ||
                md.find("flight(s) that carry one") != std::string::npos)
        << md;
    EXPECT_NE(md.find("95 % prediction intervals"), std::string::npos);
    EXPECT_EQ(md.find("nan"), std::string::npos);
}

// A flight of one vehicle has no downwash for a concealed effect to act on: the real-data proof
// says it skipped it, and with nothing else to prove on it does not pass.
TEST(RealProof, AFlightWithoutNeighboursIsSkippedAndSaidSo) {
    dw::test::TempDir d;
    auto f = crossing(2);
    f.meta.neighbours.clear();
    f.meta.vehicles.erase("n");
    dw::flight::write_flight(f, d.file("alone"));
    dw::analysis::RealProofOptions o;
    o.flights = {d.file("alone")};
    o.out_dir = d.file("proof");
    const auto r = dw::analysis::run_real_proof(o);
    EXPECT_EQ(r.skipped, std::vector<std::string>{"alone"});
    EXPECT_TRUE(r.rows.empty());
    EXPECT_FALSE(r.pass);
    EXPECT_NE(dw::read_file(r.table_path).find("Not proved on"), std::string::npos);
}

TEST(RealFlights, ConcealedEffectsAreRecoveredOnTopOfWhatEachFlightShows) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    dw::analysis::RealProofOptions o;
    for (const auto& t : dw::test::shared_trials())
        if (t.name == "swap_ss" || t.name == "randomwalk_cf50") o.flights.push_back(import_trial(t, d));
    o.physics = dw::physics::load_physics(dw::test::crazyflie_uncalibrated_physics());
    o.out_dir = d.file("proof");
    const auto r = dw::analysis::run_real_proof(o);
    ASSERT_EQ(r.rows.size(), 10u);         // per flight: the untouched one on its own fit, and four concealed effects
    std::map<std::string, int> recovered;  // per concealed effect, on how many flights
    for (const auto& row : r.rows) {
        SCOPED_TRACE(row.formation + " " + row.name);
        if (row.name == "untouched") {
            EXPECT_TRUE(row.pass) << "nothing new may be claimed on the untouched flight: " << row.found;
            continue;
        }
        // Each concealed effect is recovered — accepted, its expected value (what the untouched flight
        // shows of it, combined with the concealed value) inside its interval, nothing else claimed —
        // or, where the flight cannot carry the held-out test (its held-out evidence in fewer than 9
        // effective pieces, so the sum over pieces cannot reach z 3), the report says it is not
        // identifiable from that flight (the force scale on the swap's six encounters: docs/REAL.md).
        // Since issue 68 the published law's wrong shape is no longer stood in for by the flight's
        // own fit (its force scale moves along the push and is refused), so on top of this
        // uncalibrated physics a concealed effect may also be: recovered with another effect claimed
        // beside it, reported as its family, or refused with the report saying why (its value moves
        // along an axis of the flight, or it falls short of the discrepancy) — or lost: on these two
        // flights 3 of 8 concealed rows are recovered (8 of 8, one of them not identifiable, before
        // issue 68); the random walk's own fit is now empty and its four rows are lost (docs/REAL.md).
        const std::string dir = o.out_dir + "/" + row.formation + "/" + row.name;
        const auto report = nlohmann::json::parse(dw::read_file(dir + "/report.json"));
        // What is asserted row by row: a row counted as recovered or not identifiable holds the
        // expected value in its interval (the rows lost on this physics: docs/REAL.md).
        if (row.pass || row.not_identifiable) EXPECT_TRUE(row.covered) << row.truth << " vs " << row.fitted;
        recovered[row.name] += row.pass ? 1 : 0;
        if (row.not_identifiable) {  // and the flight's report says so, in both its forms
            const auto& j = report;
            bool labelled = false;
            for (const auto& c : j["candidates"])
                if (c["effect"] == row.name && c.contains("not_identifiable"))
                    labelled = std::sqrt(c["not_identifiable"]["evidence_pieces"].get<double>()) <
                               dw::analysis::ExplainOptions{}.min_t;
            EXPECT_TRUE(labelled);
            EXPECT_NE(dw::read_file(dir + "/report.md").find("Not identifiable from this flight: " + row.name),
                      std::string::npos);
        }
    }
    int recovered_any = 0, kept = 0;
    for (const auto& [name, flights] : recovered) recovered_any += flights > 0 ? 1 : 0;
    for (const auto& row : r.rows) kept += row.name != "untouched" && (row.pass || row.not_identifiable) ? 1 : 0;
    EXPECT_GE(recovered_any, 2) << dw::read_file(r.table_path);  // of the four effects (docs/REAL.md)
    EXPECT_GE(kept, 3) << dw::read_file(r.table_path);           // of the eight concealed rows
    EXPECT_TRUE(fs::exists(r.table_path));
}

// Issue 41: trained on some trials and tested on trials never seen (one per vehicle mix that has
// two or more), against the physics calibrated without them: the learnt models on the physics
// beat the authors' onboard network (the binary logs' ctrlFa.Faz, the "reference" row) on the
// same samples, RMSE and peak error, with one neighbour and with two, and on the three-vehicle
// trials Deep Sets is no worse than the naive sum, on the physics and alone (it starts from the sum
// model that validates better: the naive sum, here). Alone, the learnt models see each
// body's mass (a 32 g neighbour's jet from a 67 g one's): every one has a lower peak error per
// encounter than the network, and with one neighbour a lower RMSE (without the masses, 0.061-0.079 N
// peak against the network's 0.063). The corrections are validated on
// whole seen trials and shrunk by them: on f_d what they learnt does not carry over (factor 0 at
// both sizes), so on f_d they are the physics (docs/REAL.md says so). Small size (40 epochs, one
// Deep Sets training, a short calibration); docs/REAL.md has the full-size table.
TEST(RealFlights, OnUnseenTrialsTheModelsOnThePhysicsBeatTheOnboardNetwork) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    const std::vector<std::string> unseen_names{"swap_ss_03", "swap_sl_04", "swap_ll_01", "swap_sss_01", "swap_ssl_00"};
    dw::predictor::RealOptions o;
    dw::analysis::CalibrateOptions c;
    for (const auto& t : dw::importer::collection_trials(dw::test::kNeuralSwarm)) {
        if (t.logs.size() < 2) continue;
        const std::string dir = d.file(t.name);
        dw::flight::write_flight(dw::importer::neural_swarm_importer().import(t.logs, {}), dir);
        o.data.push_back(dir);
        const bool unseen = std::find(unseen_names.begin(), unseen_names.end(), t.name) != unseen_names.end();
        (unseen ? o.unseen : c.flights).push_back(dir);
    }
    ASSERT_EQ(o.unseen.size(), unseen_names.size());
    c.physics = dw::physics::load_physics(dw::test::crazyflie_uncalibrated_physics());
    c.out_dir = d.file("calibration");
    c.jobs = 1;
    c.stride = 4;
    c.max_iterations = 10;
    c.fold_iterations = 1;
    o.physics = dw::analysis::calibrate(c).calibrated;  // never saw the unseen trials
    o.out_dir = d.file("real");
    o.max_epochs = 40;
    o.members = 1;
    const auto r = dw::predictor::run_real(o);
    std::map<std::string, std::map<std::string, const dw::predictor::ComparisonRow*>> by;
    for (const auto& row : r.table) by[row.formation][row.model] = &row;
    ASSERT_EQ(by.size(), 2u);
    for (const auto& [formation, models] : by) {
        SCOPED_TRACE(formation);
        ASSERT_TRUE(models.count("reference") && models.count("physics+deep_sets"));
        const auto& ref = *models.at("reference");
        const auto& best = *std::min_element(models.begin(), models.end(), [](const auto& a, const auto& b) {
                                const bool la = a.first.starts_with("physics+"), lb = b.first.starts_with("physics+");
                                return la != lb ? la : a.second->rmse[2] < b.second->rmse[2];
                            })->second;
        for (const auto& [name, row] : models)
            std::printf("%s: %s f_d RMSE %.4f peak %.4f\n", formation.c_str(), name.c_str(), row->rmse[2],
                        row->peak_error);
        EXPECT_LT(best.peak_error, ref.peak_error) << best.model;
        EXPECT_LT(best.rmse[2], ref.rmse[2]) << best.model;
        // Issue 71: the calibrated physics' 95 % intervals (its noise model, fitted on the seen
        // trials) hold 90-97 % of the unseen trials' f_d samples (0.936 and 0.921 at full size).
        EXPECT_GE(models.at("physics")->coverage_f_d, 0.90);
        EXPECT_LE(models.at("physics")->coverage_f_d, 0.97);
        // Learnt alone, with each body's mass as an input: a lower peak error than the network, and
        // with one neighbour a lower RMSE (with two, whether the RMSE is lower depends on the seed).
        for (const char* alone : dw::predictor::kModelKinds) {
            EXPECT_LT(models.at(alone)->peak_error, ref.peak_error) << alone;
            if (formation.find("K=2") == std::string::npos) EXPECT_LT(models.at(alone)->rmse[2], ref.rmse[2]) << alone;
        }
        if (formation.find("K=2") != std::string::npos) {
            EXPECT_LE(models.at("physics+deep_sets")->rmse[2], models.at("naive_linear")->rmse[2]);
            EXPECT_LE(models.at("deep_sets")->rmse[2], models.at("naive_linear")->rmse[2]) << "alone";
        }
    }
    const auto md = dw::read_file(r.markdown_path, "table");
    EXPECT_NE(md.find("onboard interaction network"), std::string::npos);
    EXPECT_NE(md.find("leave-trials-out"), std::string::npos);
    EXPECT_NE(md.find("one whole flight of each vehicle mix flown twice or more validates"), std::string::npos) << md;
    EXPECT_NE(md.find("physics+deep_sets: f_n "), std::string::npos) << "the shrink factors are reported";
    EXPECT_NE(md.find("Deep Sets starts from naive_linear (validation f_d RMSE"), std::string::npos) << md;
}

// ---- Sessions (issue 71): several flights of one rig explained as one.

namespace {

// A synthetic recording of crossing(passes): the wrench the physics predicts with the stand's clock
// `clock_s` late, plus white noise of 3 mN.
Flight clocked_crossing(int passes, double clock_s, std::uint64_t seed) {
    Flight f = crossing(passes);
    dw::physics::PhysicsConfig hidden;
    dw::physics::clock_effect().set(hidden.effects, {clock_s});
    const dw::analysis::Resimulation r(f, {});
    const auto w = r.recorded(hidden);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> noise(0, 0.003);
    for (std::size_t i = 0; i < f.wrench.size(); ++i)
        for (std::size_t a = 0; a < 3; ++a) f.wrench[i].w[a] = w[i][a] + noise(rng);
    return f;
}

// crossing(passes) recorded with the jets' turbulence of intensity i (the push's scatter 2 i p) over 3 mN of noise.
Flight turbulent_crossing(int passes, double i, std::uint64_t seed) {
    Flight f = crossing(passes);
    const dw::analysis::Resimulation r(f, {});
    dw::physics::PhysicsConfig plain;
    plain.turbulence.enabled = false;
    const auto w = r.recorded(plain);
    std::mt19937_64 rng(seed);
    std::normal_distribution<double> unit(0, 1);
    for (std::size_t k = 0; k < f.wrench.size(); ++k)
        for (std::size_t a = 0; a < 3; ++a) f.wrench[k].w[a] = w[k][a] * (1 + 2 * i * unit(rng)) + 0.003 * unit(rng);
    return f;
}

dw::analysis::SessionResult session_of(const std::vector<double>& clocks) {
    std::vector<Flight> flights;
    std::vector<std::string> names;
    for (std::size_t k = 0; k < clocks.size(); ++k) {
        flights.push_back(clocked_crossing(12 + static_cast<int>(k), clocks[k], 7 + k));
        names.push_back("flight_" + std::to_string(k));
    }
    dw::analysis::SessionOptions o;
    o.flight_effects = false;
    return dw::analysis::explain_session(flights, names, o);
}

// The message of the dw::InputError that f throws ("" when it throws none).
template <class F>
std::string input_error_of(F f) {
    try {
        f();
    } catch (const dw::InputError& e) {
        return e.what();
    }
    return "";
}

const dw::analysis::RigCandidate* first_round(const dw::analysis::SessionResult& r, const std::string& effect) {
    for (const auto& c : r.candidates)
        if (c.effect.name == effect && c.round == 1) return &c;
    return nullptr;
}

}  // namespace

// One clock offset on every flight of a session: fitted jointly, its interval holds the truth, it is
// one value (Cochran's Q under its limit) and it is accepted — or named with its family. The same
// rig with a clock that differs from flight to flight: refused as not one value, and said so.
TEST(Session, ARigEffectSharedByEveryFlightIsFoundJointlyAndOneThatDiffersIsRefused) {
    const double truth = 0.04;
    const auto same = session_of({truth, truth, truth, truth});
    const auto* clock = first_round(same, "clock_offset");
    ASSERT_NE(clock, nullptr);
    EXPECT_TRUE(clock->one_value) << clock->note;
    EXPECT_LE(clock->lo, truth);
    EXPECT_GE(clock->hi, truth);
    ASSERT_FALSE(same.accepted.empty()) << same.verdict;
    const auto& a = same.accepted.front();
    const bool named = a.effect.name == "clock_offset" ||
                       std::find(a.family_alike.begin(), a.family_alike.end(), "clock_offset") != a.family_alike.end();
    EXPECT_TRUE(named) << same.verdict;
    EXPECT_EQ(clock->per_flight.size(), 4u);

    const auto differ = session_of({0.0, 0.08, 0.16, 0.24});
    const auto* moved = first_round(differ, "clock_offset");
    ASSERT_NE(moved, nullptr);
    EXPECT_FALSE(moved->one_value) << moved->note;
    EXPECT_FALSE(moved->accepted);
    for (const auto& c : differ.accepted) EXPECT_NE(c.effect.name, "clock_offset") << differ.verdict;
    EXPECT_NE(moved->note.find("not one value for the session"), std::string::npos) << moved->note;
}

// A session is two flights or more, each with a neighbour: else one clear error naming the flight.
TEST(Session, TooFewFlightsOrAFlightWithoutNeighbourIsOneClearError) {
    dw::analysis::SessionOptions o;
    const std::vector<Flight> one{clocked_crossing(12, 0, 1)};
    EXPECT_NE(input_error_of([&] { dw::analysis::explain_session(one, {"a"}, o); }).find("2 flights or more"),
              std::string::npos);
    auto alone = crossing(12);
    alone.meta.neighbours.clear();
    alone.meta.vehicles.erase("n");
    const std::vector<Flight> two{clocked_crossing(12, 0, 1), alone};
    EXPECT_NE(input_error_of([&] {
                  dw::analysis::explain_session(two, {"a", "b"}, o);
              }).find("b: meta.json"),
              std::string::npos);
}

// The Done-when at small size: one session of five shared trials (the proof's are ten: the shared
// trials differ by nature and five do not resolve every effect — docs/REAL.md), a timing effect
// concealed in every flight at a size one flight alone rarely shows (kSessionConcealed): on top of the
// session's own fit it is recovered (accepted with the expected value inside its interval) or named
// with its family, never as the other member alone, and the untouched session claims nothing new.
// docs/REAL.md has the full table (every session of the collection, every rig effect).
TEST(RealSession, ATimingEffectConcealedInEveryFlightIsFoundByTheSession) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir d;
    dw::analysis::SessionProofOptions o;
    for (const auto& t : dw::test::shared_trials())
        if (t.name != "randomwalk_cf51") o.flights.push_back(import_trial(t, d));
    ASSERT_EQ(o.flights.size(), 5u);
    o.physics = dw::physics::load_physics(dw::test::crazyflie_physics());
    o.out_dir = d.file("proof");
    o.cases = {"clock_offset", "sensor_lag"};
    o.session_size = 5;
    const auto r = dw::analysis::run_session_proof(o);
    const std::string table = dw::read_file(r.table_path);
    ASSERT_EQ(r.rows.size(), 3u) << table;
    EXPECT_EQ(r.clean, 1u) << table;
    for (const auto& row : r.rows) {
        SCOPED_TRACE(row.concealed);
        EXPECT_TRUE(row.pass) << row.why << "\n" << table;
        if (!row.untouched) EXPECT_LT(row.alone, row.flights) << "not below what one flight shows";
    }
    EXPECT_TRUE(fs::exists(o.out_dir + "/session_1/clock_offset/session.json"));
}

// A session's natural spreads come back from its session.json (keyed as the session keys them); a
// file that is not a session report, or names an unknown effect, is one clear error naming it.
TEST(Session, TheSpreadsOfAnEarlierSessionAreReadBackFromItsReport) {
    dw::test::TempDir d;
    std::vector<Flight> flights{clocked_crossing(12, 0.0, 1), clocked_crossing(13, 0.08, 2)};
    dw::analysis::SessionOptions o;
    o.flight_effects = false;
    const auto r = dw::analysis::explain_session(flights, {"a", "b"}, o);
    dw::analysis::write_session_report(flights, r, o, d.file("s"));
    const auto spreads = dw::analysis::spreads_from(d.file("s") + "/session.json");
    const auto* clock = first_round(r, "clock_offset");
    ASSERT_NE(clock, nullptr);
    ASSERT_TRUE(spreads.count("clock_offset"));
    EXPECT_DOUBLE_EQ(spreads.at("clock_offset"), clock->between_sd);
    EXPECT_GT(clock->between_sd, 0.0) << "two clocks 0.08 s apart";
    EXPECT_NE(dw::read_file(d.file("s") + "/session.md").find("## What this session can resolve"), std::string::npos);
    EXPECT_NE(dw::read_file(d.file("s") + "/session.json").find("\"flights_to_halve\""), std::string::npos);
    dw::write_file(d.file("bad.json"), R"({"format": "downwash-flight/1"})");
    EXPECT_NE(input_error_of([&] { dw::analysis::spreads_from(d.file("bad.json")); }).find("not a session report"),
              std::string::npos);
    dw::write_file(
        d.file("unknown.json"),
        R"({"format": "downwash-session/1", "rig_candidates": [{"round": 1, "effect": "x", "between_flight_sd": 1}]})");
    EXPECT_NE(input_error_of([&] { dw::analysis::spreads_from(d.file("unknown.json")); }).find("unknown effect 'x'"),
              std::string::npos);
}

// Issue 71, item 2: the report shares the held-out variance out — noise, turbulence, the accepted
// effects, the learnt discrepancy, unexplained — adding to 1. A flight with a clock hidden in it is
// mostly the effect's, and once it is found what is left is the noise; an untouched one is noise.
TEST(NoiseShares, TheHeldOutVarianceIsSharedOutAndTurbulenceLeftOutIsAFinding) {
    dw::analysis::ExplainOptions o;
    const auto clocked = dw::analysis::explain(clocked_crossing(12, 0.06, 3), o);
    const auto& v = clocked.shares;
    EXPECT_EQ(v.axis, 2);
    EXPECT_NEAR(v.noise + v.turbulence + v.effects + v.discrepancy + v.unexplained, 1.0, 1e-9);
    ASSERT_FALSE(clocked.accepted.empty()) << dw::analysis::verdict_line(clocked);
    EXPECT_GT(v.effects, 0.5);
    EXPECT_TRUE(v.to_the_noise);
    const auto untouched = dw::analysis::explain(clocked_crossing(12, 0.0, 3), o);
    EXPECT_TRUE(untouched.accepted.empty()) << dw::analysis::verdict_line(untouched);
    EXPECT_GT(untouched.shares.noise, 0.8);
    EXPECT_TRUE(untouched.shares.to_the_noise);
    // Turbulence the physics leaves out is a finding, with its intensity where it is measured.
    o.physics.turbulence.enabled = false;
    const auto turbulent = dw::analysis::explain(turbulent_crossing(12, 0.2, 4), o);
    ASSERT_FALSE(turbulent.turbulence.empty());
    for (const auto& b : turbulent.turbulence) EXPECT_NEAR(b.intensity, 0.2, 0.04) << b.samples << " samples";
    const auto line = dw::analysis::turbulence_line(turbulent, 0);
    EXPECT_NE(line.find("Left out: turbulence, intensity 0.2"), std::string::npos) << line;
    EXPECT_EQ(dw::analysis::turbulence_line(turbulent, 0.2).find("Left out"), std::string::npos);
    // The explainer's noise is the physics' own noise model (physics/prediction_noise.hpp): one whose
    // push share is the hidden turbulence's (2 I) counts that scatter as turbulence, not unexplained.
    o.physics.prediction_noise = {dw::physics::kPushSharePerIntensity * 0.2, 0};
    const auto counted = dw::analysis::explain(turbulent_crossing(12, 0.2, 4), o);
    EXPECT_GT(counted.shares.turbulence, 0.5);  // 0 without it
    EXPECT_LT(counted.shares.unexplained, 0.5 * turbulent.shares.unexplained);
    EXPECT_EQ(dw::analysis::turbulence_line(counted, dw::physics::counted_intensity(o.physics.prediction_noise))
                  .find("Left out"),
              std::string::npos);
}

// What a session can resolve: its interval's half-width; the flights like these that would resolve
// a given half-width scale it by t(n - 1) / sqrt(n). Five flights resolving ±0.1 (t(4) 2.776: each
// flight's pooled spread 0.1 / 2.776 × √5 = 0.0806) resolve ±0.1 themselves, and ±0.05 takes 13
// (t(12) / √13 = 0.601 ≤ 0.05 / 0.0806 = 0.621 < t(11) / √12 = 0.631).
TEST(Session, SaysWhatItCanResolveAndHowManyFlightsWouldHalveIt) {
    dw::analysis::RigCandidate c;
    c.per_flight.assign(5, dw::analysis::FlightFit{1.0, 0.01, false});
    c.dof = 4;
    c.lo = 0.9, c.hi = 1.1;
    EXPECT_NEAR(c.resolution(), 0.1, 1e-12);
    EXPECT_EQ(c.flights_to_resolve(0.1 + 1e-9), 5u);
    EXPECT_EQ(c.flights_to_resolve(0.05), 13u);
    EXPECT_EQ(c.flights_to_resolve(1e-9), 0u) << "beyond any session a lab flies";
    c.lo = -INFINITY;
    EXPECT_EQ(c.flights_to_resolve(0.05), 0u) << "no interval";
}
