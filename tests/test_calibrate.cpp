// Issue 41: the physics per vehicle class, and its calibration on many flights — a jet law hidden in
// simulated flights recovered, and on the shared Neural-Swarm trials (read from ../shared in place;
// skipped with the reason when absent) the calibrated physics predicting trials it left out.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <random>

#include "analysis/calibrate.hpp"
#include "analysis/calibration_report.hpp"
#include "analysis/explain.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/stats.hpp"
#include "flight/flight.hpp"
#include "importer/neural_swarm.hpp"
#include "physics/config.hpp"
#include "physics/flight_sim.hpp"
#include "physics/jet.hpp"
#include "real_data.hpp"
#include "support.hpp"

using namespace dw::physics;
namespace fs = std::filesystem;

namespace {

VehicleClass small_class() {
    VehicleClass k;
    k.name = "small";
    k.vehicle = {0.032, 4, 0.0225, 0.092};
    k.jet = {7.0, 4.0, 0.05};
    k.drag_coefficient = 0.9;
    k.kv_omega_n_per_mps = 0.02;
    return k;
}

}  // namespace

TEST(VehicleClasses, AClassGivesItsVehiclesItsJetAndItsSufferersDragAndThrustLoss) {
    PhysicsConfig c;
    c.classes.push_back(small_class());
    const VehicleParams small = c.classes[0].vehicle;
    const Jet j = Jet::make(small, c), other = Jet::make(c.neighbour, c);
    EXPECT_DOUBLE_EQ(j.centreline(0.5), j.u_hover * 7.0 / (0.5 / 0.092 + 4.0));
    EXPECT_DOUBLE_EQ(j.half_width(0.5), 0.05 * (0.5 / 0.092 + 4.0) * 0.092);
    EXPECT_DOUBLE_EQ(other.centreline(0.5), other.u_hover * 10.11 / (0.5 / 0.25 + 5.817))
        << "a vehicle no class matches keeps the configuration's coefficients";
    EXPECT_DOUBLE_EQ(sufferer_as(c, small).kv_omega_n_per_mps, 0.02);
    EXPECT_DOUBLE_EQ(sufferer_as(c, small).drag_coefficient, 0.9);
    EXPECT_DOUBLE_EQ(sufferer_as(c, c.neighbour).drag_coefficient, c.sufferer.drag_coefficient);
    VehicleParams near_small = small;
    near_small.mass_kg *= 1.01;
    EXPECT_EQ(class_of(c, near_small), nullptr) << "another vehicle is another class";

    const PhysicsConfig back = parse_physics(to_yaml(c), "round.yaml");
    ASSERT_EQ(back.classes.size(), 1u);
    EXPECT_EQ(back.classes[0].name, "small");
    EXPECT_DOUBLE_EQ(back.classes[0].jet.origin, 4.0);
    EXPECT_DOUBLE_EQ(back.classes[0].kv_omega_n_per_mps, 0.02);
    try {
        parse_physics("format: downwash-physics/1\nclasses:\n  - {name: a, jet: {strength: -1}}\n", "bad.yaml");
        ADD_FAILURE() << "a negative jet strength was accepted";
    } catch (const dw::InputError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("bad.yaml:3"), std::string::npos) << what;
        EXPECT_NE(what.find("strength"), std::string::npos) << what;
    }
}

// A trial left out is predicted and explained by a calibration that did not see it: its jets, and
// the turbulence its explanation counts as noise. One trial's flight is simulated with turbulent
// jets, two without: pooled over the three the residual's spread grows with the push, but the
// turbulent trial, left out, gets only the quiet trials' intensity.
TEST(PhysicsCalibration, EachTrialLeftOutGetsTheTurbulenceOfTheOtherTrials) {
    PhysicsConfig quiet;
    quiet.turbulence.enabled = false;
    quiet.stand.noise_n = 0.005;
    PhysicsConfig turbulent = quiet;
    turbulent.turbulence.enabled = true;
    turbulent.turbulence.intensity = 0.3;
    dw::test::TempDir dir;
    dw::analysis::CalibrateOptions o;
    for (int i = 0; i < 3; ++i) {
        FlyOptions fo;
        fo.grid.legs = 3;
        fo.seed = 21 + static_cast<std::uint64_t>(i);
        o.flights.push_back(dir.file("flight" + std::to_string(i)));
        dw::flight::write_flight(simulate_flight(i == 0 ? turbulent : quiet, fo).flight, o.flights.back());
    }
    o.physics = quiet;
    o.out_dir = dir.file("cal");
    o.max_iterations = 5;
    o.fold_iterations = 2;
    const auto r = dw::analysis::calibrate(o);
    // Quiet flights alone give I about 0.003 (2I 0.006-0.007: the test above).
    constexpr double kQuiet = 0.02, kTurbulent = 0.05;
    EXPECT_GT(r.turbulence_intensity, kTurbulent);
    ASSERT_EQ(r.trials.size(), 3u);
    for (const auto& t : r.trials) {
        ASSERT_EQ(t.flights.size(), 1u) << t.trial;
        if (t.flights[0] == o.flights[0]) EXPECT_LT(t.turbulence_intensity, kQuiet) << "the turbulent trial's own fold";
        else EXPECT_GT(t.turbulence_intensity, kTurbulent) << t.trial << ": a fold with the turbulent trial";
        // Issue 71: the held-out residual standardised by the noise model says whether it holds — the
        // turbulent trial under a fold that found no turbulence is far beyond 1 (12.7 here); the quiet
        // ones, under a fold that counts the turbulent trial's, are below 1 (0.7).
        if (t.flights[0] == o.flights[0]) EXPECT_GT(t.z_rms_heldout, 2 * dw::analysis::kStandardisedBand.hi);
        else EXPECT_LT(t.z_rms_heldout, 1.0) << t.trial;
    }
    // The noise model the standardisation takes is fitted per fold: the push's share of the scatter
    // is larger in the folds that hold the turbulent trial.
    const auto own_fold =
        std::find_if(r.trials.begin(), r.trials.end(), [&](const auto& t) { return t.flights[0] == o.flights[0]; });
    for (const auto& t : r.trials)
        if (&t != &*own_fold) EXPECT_GT(t.noise.push_share, 2 * own_fold->noise.push_share) << t.trial;
}

// Flights simulated with a jet law other than the configuration's: calibrated from the published
// coefficients, each is recovered inside its interval, and every trial left out is predicted
// better than by the uncalibrated physics.
TEST(PhysicsCalibration, RecoversAJetLawHiddenInSimulatedFlightsAndPredictsTheTrialsItLeftOut) {
    PhysicsConfig truth;
    truth.turbulence.enabled = false;
    truth.stand.noise_n = 0.005;
    VehicleClass k;
    k.name = "hidden";
    k.vehicle = truth.neighbour;
    k.jet = {7.0, 3.5, 0.1};
    k.drag_coefficient = truth.sufferer.drag_coefficient;
    k.kv_omega_n_per_mps = truth.sufferer.kv_omega_n_per_mps;
    truth.classes.push_back(k);
    dw::test::TempDir dir;
    dw::analysis::CalibrateOptions o;
    const char* formations[] = {"single", "stack", "leader_follower"};
    for (int i = 0; i < 3; ++i) {
        FlyOptions fo;
        fo.formation = formations[i];
        fo.grid.legs = 9;  // three at each altitude, over and beside the stand
        fo.grid.lines_n_m = {0.0, 0.15, -0.15};
        fo.seed = 11 + static_cast<std::uint64_t>(i);
        const std::string folder = dir.file(formations[i]);
        dw::flight::write_flight(simulate_flight(truth, fo).flight, folder);
        o.flights.push_back(folder);
    }
    o.physics = truth;
    o.physics.classes.clear();
    o.out_dir = dir.file("cal");
    o.stride = 2;
    o.explain_heldout = true;
    const auto r = dw::analysis::calibrate(o);
    ASSERT_EQ(r.parameters.size(), 4u);  // one class, producer and sufferer
    const double hidden[] = {7.0, 0.1, 3.5, k.kv_omega_n_per_mps};
    for (std::size_t p = 0; p < 4; ++p) {
        const auto& x = r.parameters[p];
        EXPECT_LE(x.lo, hidden[p]) << x.name << " " << x.value;
        EXPECT_GE(x.hi, hidden[p]) << x.name << " " << x.value;
    }
    for (std::size_t p = 0; p < 3; ++p)  // the jet's three coefficients, each to a few per cent
        EXPECT_NEAR(r.parameters[p].value, hidden[p], 0.05 * hidden[p]) << r.parameters[p].name;
    ASSERT_EQ(r.trials.size(), 3u);
    for (const auto& t : r.trials) {
        EXPECT_LT(t.rmse_heldout, 0.5 * t.rmse_before) << t.trial;
        // Explained against the calibration without it, nothing is left for the explainer to claim,
        // and its held-out error is within a few noise floors (the published law leaves ~16 here:
        // 0.17 N against a floor of 0.01 N; the jet's coefficients, fitted to a few per cent, leave
        // 1.5-1.7 at this signal-to-noise).
        ASSERT_EQ(t.explained_ratio.size(), 1u) << t.trial;
        EXPECT_LT(t.explained_ratio[0], 2.5) << t.trial;
        const auto report =
            nlohmann::json::parse(dw::read_file(dir.file("cal/folds/" + t.trial + "/" + t.trial + "/report.json")));
        // Nothing material: since issue 68 the leader follower's fold claims a force scale of 1.0017
        // (held-out z 3.8 on f_d; its value moves along no axis beyond z 2.2), within 1 % of the search
        // range of neutral — the jet's coefficients fitted to a few per cent leave that much.
        for (const auto& c : dw::analysis::all_effects())
            for (const auto& a : report["candidates"])
                if (a["effect"] == c.name && a["accepted"].get<bool>())
                    for (const auto& p : c.params)
                        if (a["params"].contains(p.name))
                            EXPECT_NEAR(a["params"][p.name].get<double>(), p.start, 0.01 * (p.fit_max - p.fit_min))
                                << t.trial << ": " << c.name;
        EXPECT_NE(report["physics_calibration"].get<std::string>().find("without " + t.trial), std::string::npos);
        const PhysicsConfig fold = load_physics(dir.file("cal/folds/" + t.trial + "/physics.yaml"));
        EXPECT_NEAR(fold.turbulence.enabled ? fold.turbulence.intensity : 0.0, t.turbulence_intensity, 1e-9) << t.trial;
    }
    const PhysicsConfig written = load_physics(r.physics_path);
    ASSERT_EQ(written.classes.size(), 1u);
    EXPECT_NEAR(written.classes[0].jet.strength, r.parameters[0].value, 1e-6);
    const auto j = nlohmann::json::parse(dw::read_file(dir.file("cal/calibration.json")));
    EXPECT_EQ(j["trials"].size(), 3u);
    EXPECT_GT(fs::file_size(dir.file("cal/pairing_1.png")), 1000u);
    // Flights without turbulence: what the calibration leaves does not grow with the push (measured
    // 2I 0.006-0.007; the shared trials' small sufferers 0.26-0.36, below).
    ASSERT_FALSE(j["residual_by_force"].empty());
    for (const auto& p : j["residual_by_force"]) EXPECT_LT(p["two_i"].get<double>(), 0.05) << p["pairing"];
}

TEST(PhysicsCalibration, OneTrialIsRefusedInOneLine) {
    dw::test::TempDir dir;
    FlyOptions fo;
    fo.formation = "single";
    fo.grid.legs = 5;
    auto f = simulate_flight(PhysicsConfig{}, fo).flight;
    // Issue 70: a source whose collection is not a string is no name (the JSON library's own
    // "type must be string" was the line).
    f.meta.extra_json = R"({"source": {"collection": 5, "logs": ["a.csv"]}})";
    dw::flight::write_flight(f, dir.file("one"));
    dw::analysis::CalibrateOptions o;
    o.flights = {dir.file("one"), dir.file("one")};
    o.out_dir = dir.file("cal");
    try {
        dw::analysis::calibrate(o);
        ADD_FAILURE() << "one trial was calibrated on";
    } catch (const dw::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("needs at least two"), std::string::npos) << e.what();
    }
}

namespace {

// Every shared trial, imported (one flight each, the lowest vehicle the sufferer; a vehicle alone too).
std::vector<std::string> import_collection(const dw::test::TempDir& dir) {
    std::vector<std::string> flights;
    for (const auto& t : dw::importer::collection_trials(dw::test::kNeuralSwarm)) {
        const std::string folder = dir.file(t.name);
        dw::flight::write_flight(dw::importer::neural_swarm_importer().import(t.logs, {}), folder);
        flights.push_back(folder);
    }
    return flights;
}

}  // namespace

// A flight of one vehicle: its f_d and its line against the vehicle's own vertical velocity.
TEST(Calibration, AVehicleAloneIsMeasuredNotFitted) {
    dw::flight::Flight f;
    f.meta.sufferer = "s";
    f.meta.stand_height_m.reset();
    f.meta.wrench_source = dw::flight::WrenchSource::residual;
    const auto s = f.body_index("s");
    for (int i = 0; i <= 3000; ++i) {  // d = -1 + 0.2 sin t, so v_d = 0.2 cos t; f_d = 0.01 - 0.02 v_d
        const double t = i * 0.01;
        f.poses.push_back({t, s, {0, 0, -1.0 + 0.2 * std::sin(t)}, {1, 0, 0, 0}});
        if (i % 2 == 0) f.wrench.push_back({t, {0, 0, 0.01 - 0.02 * 0.2 * std::cos(t), 0, 0, 0}});
    }
    const auto a = dw::analysis::measure_alone(f, "alone", "a class");
    EXPECT_EQ(a.flight, "alone");
    EXPECT_EQ(a.samples, 1501u);  // every sample: 0.8 m or higher
    EXPECT_NEAR(a.slope_per_v_d, -0.02, 1e-4);
    EXPECT_NEAR(a.mean_f_d, 0.01, 2e-4);
    EXPECT_LT(a.rms_after_line, 1e-4);
    EXPECT_GT(a.rms_f_d, 0.01);
    for (auto& p : f.poses) p.p[2] = -0.1;  // low, where a flight alone may touch the floor: not counted
    EXPECT_THROW(dw::analysis::measure_alone(f, "alone", "a class"), dw::InputError);
}

// Issue 41 ("the residual's own lag where the source's thrust model leaves one"): flying alone,
// a vehicle's residual is its own error, and the thrust's lag that the authors chose (0.84 per
// sample) is where it spreads least off the floor (measured as calibrate reports a flight alone):
// no lag, or a longer one, spreads it wider (docs/REAL.md measures 0-0.95). The lag used is in
// meta.json; one outside [0, 0.99] is refused.
TEST(RealCalibration, TheSourcesThrustLagIsWhereAVehicleAlonesResidualSpreadsLeast) {
    REQUIRE_SHARED_DATA();
    using namespace dw::importer;
    std::map<std::string, std::vector<std::string>> by;
    for (const auto& t : collection_trials(dw::test::kNeuralSwarm)) by[t.name] = t.logs;
    for (const auto* alone : {"randomwalk_s_00", "randomwalk_l_01"}) {
        SCOPED_TRACE(alone);
        ASSERT_EQ(by[alone].size(), 1u);
        std::map<double, double> spread;
        for (double lag : {0.0, kAuthorsThrustLag, 0.95}) {
            ImportOptions o;
            o.thrust_lag = lag;
            const auto f = neural_swarm_importer().import(by[alone], o);
            EXPECT_EQ(nlohmann::json::parse(f.meta.extra_json)["residual"]["thrust_lag"].get<double>(), lag);
            spread[lag] = dw::analysis::measure_alone(f, alone, "alone").sd_f_d;
        }
        EXPECT_LT(spread[kAuthorsThrustLag], spread[0.0]);
        EXPECT_LT(spread[kAuthorsThrustLag], spread[0.95]);
    }
    ImportOptions bad;
    bad.thrust_lag = 1.0;
    EXPECT_THROW(neural_swarm_importer().import(by["randomwalk_s_00"], bad), dw::InputError);
}

// What is left by how hard the physics pushes: a residual that scatters by 2I x the push (a jet's
// turbulence) gives that 2I and a spread that grows band by band; noise alone gives neither.
TEST(Calibration, TheResidualsScatterByThePushGivesTheTurbulencesTwoI) {
    auto scatter = [](double two_i) {
        dw::analysis::PairingSamples p;
        std::mt19937 rng(3);
        std::uniform_real_distribution<double> push(0.0, 0.1);
        std::normal_distribution<double> unit(0.0, 1.0);
        for (int i = 0; i < 20000; ++i) {
            const double f = push(rng), recorded = f + 0.005 * unit(rng) + two_i * f * unit(rng);
            p.rows.push_back({0.1, 0.5, recorded, f, 2 * f});
        }
        return dw::analysis::scatter_of(p);
    };
    const auto turbulent = scatter(0.3), quiet = scatter(0.0);
    EXPECT_NEAR(turbulent.two_i, 0.3, 0.03);
    EXPECT_GT(turbulent.bands.back().rms, 2 * turbulent.bands.front().rms);
    EXPECT_LT(quiet.two_i, 0.05);
    EXPECT_NEAR(quiet.bands.back().rms, quiet.bands.front().rms, 0.001);
}

// What a model exact on every sample would leave, in the explainer's floor where nobody is ever far
// (successive differences): about 1 for white noise, more for noise slower than the samples.
TEST(Calibration, AnExactModelLeavesTheResidualsSlowErrorAboveTheDifferencesFloor) {
    auto ratio = [](double rho) {
        dw::flight::Flight f;
        f.meta.sufferer = "s";
        f.meta.stand_height_m.reset();
        f.meta.wrench_source = dw::flight::WrenchSource::residual;
        const auto s = f.body_index("s");
        std::mt19937 rng(7);
        std::normal_distribution<double> white(0.0, 0.005 * std::sqrt(1 - rho * rho));
        double x = 0;
        for (int i = 0; i <= 6000; ++i) {  // AR(1) noise of SD 0.005 N
            const double t = i * 0.01;
            x = rho * x + white(rng);
            f.poses.push_back({t, s, {0, 0, -1.0}, {1, 0, 0, 0}});
            f.wrench.push_back({t, {0, 0, x, 0, 0, 0}});
        }
        const auto a = dw::analysis::measure_alone(f, "alone", "a class");
        EXPECT_NEAR(a.sd_f_d, 0.005, 0.0015) << rho;
        return a.exact_model_ratio();
    };
    EXPECT_NEAR(ratio(0.0), 1.0, 0.1) << "white noise: the floor is its spread";
    EXPECT_NEAR(ratio(0.9), 1 / std::sqrt(1 - 0.9), 0.4) << "slow noise: its differences spread less";
}

// The shared trials calibrated as the command does by default (as config/physics.crazyflie.yaml
// says it was made): each trial left out in turn is predicted better than by the published jet
// law, and the shipped file holds exactly this output.
TEST(RealCalibration, TheSharedTrialsLeftOutInTurnArePredictedBetterAndTheShippedFileIsTheOutput) {
    REQUIRE_SHARED_DATA();
    dw::test::TempDir dir;
    dw::analysis::CalibrateOptions o;
    o.flights = import_collection(dir);
    ASSERT_GE(o.flights.size(), 10u);
    o.physics = load_physics(dw::test::crazyflie_uncalibrated_physics());
    o.out_dir = dir.file("cal");
    o.jobs = 1;  // one CTest slot
    const auto r = dw::analysis::calibrate(o);
    // Every flight of two vehicles or more is a trial of its own; a vehicle alone (one small, one
    // large in the collection) takes no part in the fit but is reported: its residual's own errors.
    ASSERT_EQ(r.alone.size(), 2u);
    EXPECT_EQ(r.trials.size() + r.alone.size(), o.flights.size());
    EXPECT_NE(r.alone[0].vehicle_class, r.alone[1].vehicle_class);
    for (const auto& a : r.alone) {
        EXPECT_GT(a.samples, 300u) << a.flight;
        EXPECT_GT(a.rms_f_d, 0.0) << a.flight;
        EXPECT_LE(a.rms_after_line, a.rms_f_d) << a.flight;
        // The residual's own error is slower than its jitter (measured 1.61 small, 1.45 large):
        // on a swap, where the floor is the differences' spread, even an exact model would leave
        // about that many floors (docs/REAL.md).
        EXPECT_GT(a.exact_model_ratio(), 1.3) << a.flight;
    }
    EXPECT_NE(dw::read_file(r.report_path).find("The residual with nobody near"), std::string::npos);
    // What is left grows with the push, as a jet's turbulence would make it: under a small
    // vehicle's own class, the residual's spread where the calibrated f_d is ≥ 0.06 N is 3-6 times
    // its spread below 0.01 N (measured), and 2I is 0.26-0.36 (docs/REAL.md).
    const auto j = nlohmann::json::parse(dw::read_file(dir.file("cal/calibration.json")));
    int small = 0;
    for (const auto& p : j["residual_by_force"]) {
        if (p["pairing"].get<std::string>().rfind("32 g", 0) != 0) continue;
        ++small;
        const auto& b = p["bands"];
        EXPECT_GT(b.back()["rms_n"].get<double>(), 2 * b.front()["rms_n"].get<double>()) << p["pairing"];
        EXPECT_GT(p["two_i"].get<double>(), 0.15) << p["pairing"];
    }
    EXPECT_GE(small, 3);
    std::vector<double> before, heldout;
    for (const auto& t : r.trials) before.push_back(t.rmse_before), heldout.push_back(t.rmse_heldout);
    EXPECT_LT(dw::median(heldout), 0.7 * dw::median(before)) << dw::read_file(r.report_path);
    for (const auto& p : r.parameters)
        EXPECT_TRUE(std::isfinite(p.value) && p.lo <= p.value && p.value <= p.hi) << p.vehicle_class << " " << p.name;
    const PhysicsConfig shipped = load_physics(dw::test::crazyflie_physics());
    ASSERT_EQ(shipped.classes.size(), r.calibrated.classes.size());
    for (std::size_t k = 0; k < shipped.classes.size(); ++k) {
        const auto &a = shipped.classes[k], &b = r.calibrated.classes[k];
        EXPECT_EQ(a.name, b.name);
        for (auto [x, y] : {std::pair{a.jet.strength, b.jet.strength},
                            {a.jet.width, b.jet.width},
                            {a.jet.origin, b.jet.origin},
                            {a.kv_omega_n_per_mps, b.kv_omega_n_per_mps},
                            {a.noise_floor_n, b.noise_floor_n}})
            EXPECT_NEAR(x, y, 1e-4 * std::abs(y) + 1e-9) << a.name << ": regenerate config/physics.crazyflie.yaml";
        // Issue 71: each class's floor as the sufferer, where no jet reaches (its flights' and its
        // flight alone's spread: 5.4 mN small, 11.3 mN large, measured), the intervals' start.
        EXPECT_GT(b.noise_floor_n, 0.003) << b.name;
        EXPECT_LT(b.noise_floor_n, 0.03) << b.name;
    }
    EXPECT_EQ(shipped.calibration, r.calibrated.calibration);
    // The jets' turbulence the residual shows (pooled 2I 0.20: intensity 0.10), written as the
    // calibrated physics' turbulence.
    EXPECT_GT(r.turbulence_intensity, 0.05);
    EXPECT_TRUE(r.calibrated.turbulence.enabled);
    EXPECT_TRUE(shipped.turbulence.enabled);
    EXPECT_NEAR(shipped.turbulence.intensity, r.turbulence_intensity, 1e-3)
        << "regenerate config/physics.crazyflie.yaml";
    // Issue 71: the noise model (each flight's floor where the physics predicts no push; s and tau by
    // maximum likelihood) fits the trials it never saw: the held-out residual standardised by it has
    // an RMS within kStandardisedBand on at least 80 % of them (17 of 20 measured), and the shipped
    // file carries the one fitted on all of them.
    const auto within = std::count_if(r.trials.begin(), r.trials.end(), [](const auto& t) {
        return dw::analysis::kStandardisedBand.contains(t.z_rms_heldout);
    });
    EXPECT_GE(static_cast<double>(within), 0.8 * static_cast<double>(r.trials.size())) << dw::read_file(r.report_path);
    EXPECT_NEAR(shipped.prediction_noise.push_share, r.calibrated.prediction_noise.push_share, 1e-3);
    EXPECT_NEAR(shipped.prediction_noise.timing_spread_s, r.calibrated.prediction_noise.timing_spread_s, 1e-4);
    EXPECT_GT(r.calibrated.prediction_noise.timing_spread_s, 0.0);
}

// What the calibration fixed: explained against it, the shared flights no longer buy back a
// two-fold over-prediction with their own force scale (fitted alone: 0.39-0.52 against the
// published law, docs/REAL.md; against the calibration, measured 1.0 on the swap and 1.27 on the
// random walk, and accepted on neither).
TEST(RealCalibration, TheCalibratedPhysicsNoLongerOverPredictsTheDownwash) {
    REQUIRE_SHARED_DATA();
    dw::analysis::ExplainOptions o;
    o.physics = load_physics(dw::test::crazyflie_physics());
    for (const char* trial : {"swap_ss_01", "randomwalk_ss_02"}) {
        SCOPED_TRACE(trial);
        std::vector<std::string> logs;
        for (const auto& t : dw::importer::collection_trials(dw::test::kNeuralSwarm))
            if (t.name == trial) logs = t.logs;
        const auto f = dw::importer::neural_swarm_importer().import(logs, {});
        const auto r = dw::analysis::explain(f, o);
        for (const auto& c : r.candidates)
            if (c.effect.name == "force_scale" && c.round == 1) {
                EXPECT_GT(c.values[0], 0.75);
                EXPECT_LT(c.values[0], 1.33);
            }
        for (const auto& c : r.accepted) EXPECT_NE(c.effect.name, "force_scale");
    }
}
