#include "analysis/calibrate.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>
#include <nlohmann/json.hpp>
#include <set>

#include "analysis/calibration_report.hpp"
#include "analysis/explain.hpp"
#include "analysis/noise.hpp"
#include "analysis/resimulation.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/parallel.hpp"
#include "core/shutdown.hpp"
#include "core/stats.hpp"
#include "flight/blocks.hpp"
#include "flight/flight.hpp"
#include "physics/bodies.hpp"
#include "physics/prediction_noise.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;
using physics::PhysicsConfig;
using physics::VehicleClass;
using physics::VehicleParams;

using flight::kFdAxis;                       // the axis calibrated on
constexpr int kBlocksWanted = 5;             // cross-validation blocks asked of find_blocks (for `near`)
constexpr double kStepFraction = 1e-3;       // forward-difference step, relative to the value (or start)
constexpr double kLambda0 = 1e-3;            // Levenberg-Marquardt's first damping
constexpr double kRelativeTolerance = 1e-6;  // stop when the cost falls by less than this fraction
constexpr double kLambdaMax = 1e10;          // ... or no step lowers it
constexpr double kLambdaMin = 1e-9;          // the damping never falls below this
constexpr double kStepFloor = 1e-3;          // added to the start value: a parameter starting at 0 still gets a step
constexpr double kUnusedDiagonal = 1.0;      // the normal matrix's diagonal for a parameter no flight sees

// A calibrated quantity of a class: name, unit, role, bounds, and where it lives in the class.
struct Knob {
    const char* name;
    const char* unit;
    bool producer;  // a producer's (its jet) or a sufferer's
    double lower, upper;
    double& (*of)(VehicleClass&);
};
constexpr std::array<Knob, 4> kKnobs{{
    {"jet strength", "", true, 0.5, 60, [](VehicleClass& c) -> double& { return c.jet.strength; }},
    {"jet width", "", true, 0.01, 0.5, [](VehicleClass& c) -> double& { return c.jet.width; }},
    {"jet origin", "sizes", true, 0.0, 40, [](VehicleClass& c) -> double& { return c.jet.origin; }},
    {"thrust loss kv", "N per m/s per rotor", false, 0.0, 1.0,
     [](VehicleClass& c) -> double& { return c.kv_omega_n_per_mps; }},
}};

struct FlightData {
    std::string dir;
    std::unique_ptr<Resimulation> sim;
    std::size_t trial = 0;
    std::string pairing;
    std::vector<std::size_t> rows, fit_rows;  // near samples; every stride-th of them
    std::vector<double> offset, above;        // per row: the nearest neighbour's horizontal offset, height
    std::size_t sufferer_class = 0;           // index into the configuration's classes
    std::vector<double> far_f_d;              // the measured f_d where nobody is near
};

struct Trial {
    std::string key, name;
    std::vector<std::size_t> flights;
};

std::string class_name(const VehicleParams& v) {
    return log::cat(std::lround(v.mass_kg * 1000), " g, l ", std::lround(v.motor_distance_m * 1000), " mm");
}

// The class of v in c, added (starting from c's own values) when there is none.
std::size_t class_index(PhysicsConfig& c, const VehicleParams& v) {
    if (const auto* k = physics::class_of(c, v)) return static_cast<std::size_t>(k - c.classes.data());
    VehicleClass k;
    k.name = class_name(v);
    k.vehicle = v;
    k.jet = c.bauersfeld;
    k.drag_coefficient = c.sufferer.drag_coefficient;
    k.kv_omega_n_per_mps = c.sufferer.kv_omega_n_per_mps;
    c.classes.push_back(k);
    return c.classes.size() - 1;
}

// Flights from the same logs are one trial (another sufferer of the same flight is not unseen).
std::string trial_key(const flight::Flight& f, const std::string& dir) {
    const auto j = nlohmann::json::parse(f.meta.extra_json, nullptr, false);
    if (!j.is_object() || !j.contains("source") || !j["source"].is_object() || !j["source"].contains("logs"))
        return fs::weakly_canonical(dir).string();
    std::set<std::string> logs;
    for (const auto& l : j["source"]["logs"])
        if (l.is_string()) logs.insert(l.get<std::string>());
    const auto collection = j["source"].find("collection");
    const bool named = collection != j["source"].end() && collection->is_string();
    return (named ? collection->get<std::string>() : std::string()) + " " + log::join(logs, "+");
}

}  // namespace

// The noise model a residual is standardised by (physics/prediction_noise.hpp, the predictor's
// intervals'): per flight its floor, and the scatter that grows with the push p and its rate.
struct NoiseScale {
    std::vector<double> floor;  // per flight (Calibration::flights())
    physics::PredictionNoise noise;
};

// The flights, their trials and classes, and the fit's parameters.
class Calibration {
public:
    explicit Calibration(const CalibrateOptions& o) : o_(o), config_(o.physics) {
        config_.effects = {};  // calibrated on the flow alone; effects stay the explainer's to find
        load_flights();
        if (trials_.size() < 2)
            throw InputError(log::cat("--flights: ", trials_.size(),
                                      " trial(s); calibration leaves whole trials out and needs at least two"));
        choose_parameters();
    }

    std::size_t size() const { return params_.size(); }
    const std::vector<Trial>& trials() const { return trials_; }
    const std::vector<FlightData>& flights() const { return flights_; }
    const std::vector<AloneFlight>& alone() const { return alone_; }

    // The starting values (the base's) and their bounds.
    std::vector<double> start() const {
        std::vector<double> x;
        for (const auto& p : params_) {
            VehicleClass c = config_.classes[p.cls];
            x.push_back(kKnobs[p.knob].of(c));
        }
        return x;
    }
    PhysicsConfig config_of(const std::vector<double>& x) const {
        PhysicsConfig c = config_;
        for (std::size_t i = 0; i < params_.size(); ++i) kKnobs[params_[i].knob].of(c.classes[params_[i].cls]) = x[i];
        return c;
    }
    const Knob& knob(std::size_t i) const { return kKnobs[params_[i].knob]; }
    const std::string& class_of(std::size_t i) const { return config_.classes[params_[i].cls].name; }
    // Whether parameter i acts on flight f (its class flies there in its role).
    bool acts_on(std::size_t i, std::size_t f) const { return roles_[f].count({params_[i].cls, knob(i).producer}) > 0; }

    // f_d residuals (recorded − predicted) on the fit rows of the flights in `use`, in order; with a
    // noise model, each over its standard deviation there.
    Eigen::VectorXd residuals(const std::vector<double>& x, const std::vector<std::size_t>& use, bool fit_rows,
                              const NoiseScale* noise = nullptr) const {
        const auto samples = noise_samples(x, use, fit_rows, noise ? noise->floor : std::vector<double>{});
        Eigen::VectorXd r(static_cast<Eigen::Index>(samples.size()));
        for (std::size_t k = 0; k < samples.size(); ++k) {
            const auto& s = samples[k];
            r[static_cast<Eigen::Index>(k)] =
                noise ? s.residual / physics::prediction_sd(s.floor, noise->noise, s.p, s.p_rate) : s.residual;
        }
        return r;
    }

    // The same residuals with what the noise model needs of each: its flight's floor (from `floors`,
    // per flight), the push predicted and its rate; without floors (no noise model), floor and rate 0.
    std::vector<physics::NoiseSample> noise_samples(const std::vector<double>& x, const std::vector<std::size_t>& use,
                                                    bool fit_rows, const std::vector<double>& floors) const {
        const PhysicsConfig c = config_of(x);
        std::vector<std::vector<physics::NoiseSample>> parts(use.size());
        parallel_for(use.size(), o_.jobs, [&](std::size_t k) {
            throw_if_stopped(o_.stop, "the calibration");
            const auto& fd = flights_[use[k]];
            const auto pred = fd.sim->recorded(c);
            std::vector<double> p_d;
            for (const auto& w : pred) p_d.push_back(w[kFdAxis]);
            // The rates only where a noise model is asked for (not on the fit's many residual calls).
            const auto rate =
                floors.empty() ? std::vector<double>(p_d.size(), 0.0) : physics::push_rates(fd.sim->stamps(), p_d);
            const double floor = floors.empty() ? 0.0 : floors[use[k]];
            auto& part = parts[k];
            for (auto i : fit_rows ? fd.fit_rows : fd.rows)
                part.push_back({fd.sim->measured()[i][kFdAxis] - p_d[i], floor, p_d[i], rate[i]});
            if (fd.sim->flying()) {  // its residual's own zero: a nuisance of each flight
                double bias = 0;
                for (const auto& s : part) bias += s.residual / static_cast<double>(part.size());
                for (auto& s : part) s.residual -= bias;
            }
        });
        std::vector<physics::NoiseSample> out;
        for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
        return out;
    }

private:
    struct Param {
        std::size_t cls, knob;
    };

    void load_flights() {
        std::map<std::string, std::size_t> trial_of;
        for (const auto& dir : o_.flights) {
            throw_if_stopped(o_.stop, "the calibration");
            if (o_.progress) o_.progress(log::cat("reading ", dir));
            const flight::Flight f = flight::read_flight(dir);
            if (f.meta.neighbours.empty()) {  // nobody near: the residual's own errors, not the fit's
                const auto v = physics::vehicle_of(f.meta, f.meta.sufferer, config_.sufferer.vehicle);
                const auto* k = physics::class_of(config_, v);
                alone_.push_back(measure_alone(f, dir, k ? k->name : class_name(v)));
                continue;
            }
            FlightData d;
            d.dir = dir;
            d.sim = std::make_unique<Resimulation>(f, config_);
            describe_rows(f, d);
            const auto key = trial_key(f, dir);
            auto [it, added] = trial_of.try_emplace(key, trials_.size());
            if (added) trials_.push_back({key, fs::path(dir).filename().string(), {}});
            d.trial = it->second;
            trials_[d.trial].flights.push_back(flights_.size());
            note_roles(f);
            d.sufferer_class =
                class_index(config_, physics::vehicle_of(f.meta, f.meta.sufferer, config_.sufferer.vehicle));
            d.pairing = pairing_of(f);
            flights_.push_back(std::move(d));
        }
    }

    void describe_rows(const flight::Flight& f, FlightData& d) const {
        if (!d.sim->measured_axes()[kFdAxis])
            throw InputError(log::cat(d.dir, ": wrench.csv carries no f_d measurement to calibrate on"));
        const auto blocks = flight::find_blocks(f, kBlocksWanted, physics::encounter_radii(f.meta, config_));
        const auto info = describe(*d.sim, blocks);
        for (std::size_t i = 0; i < info.size(); ++i) {
            if (!std::isfinite(d.sim->measured()[i][kFdAxis])) continue;
            if (!info[i].near) {
                d.far_f_d.push_back(d.sim->measured()[i][kFdAxis]);
                continue;
            }
            if (d.rows.size() % static_cast<std::size_t>(o_.stride) == 0) d.fit_rows.push_back(i);
            d.rows.push_back(i);
            d.offset.push_back(info[i].offset);
            d.above.push_back(info[i].above);
        }
        if (d.rows.empty()) throw InputError(log::cat(d.dir, ": no neighbour ever comes near the sufferer"));
    }

    // Which classes fly in the flight and as what: (class, producer?).
    void note_roles(const flight::Flight& f) {
        std::set<std::pair<std::size_t, bool>> r;
        r.insert({class_index(config_, physics::vehicle_of(f.meta, f.meta.sufferer, config_.sufferer.vehicle)), false});
        for (const auto& v : physics::neighbours_of(f.meta, config_)) r.insert({class_index(config_, v), true});
        roles_.push_back(r);
    }

    std::string pairing_of(const flight::Flight& f) const {
        std::vector<std::string> above;
        for (const auto& v : physics::neighbours_of(f.meta, config_)) above.push_back(class_name(v));
        std::sort(above.begin(), above.end());
        return log::cat(class_name(physics::vehicle_of(f.meta, f.meta.sufferer, config_.sufferer.vehicle)), " under ",
                        log::join(above, " + "));
    }

    // Every knob of every class that plays its role in some flight.
    void choose_parameters() {
        for (std::size_t c = 0; c < config_.classes.size(); ++c)
            for (std::size_t k = 0; k < kKnobs.size(); ++k) {
                const bool used = std::any_of(roles_.begin(), roles_.end(), [&](const auto& r) {
                    return r.count({c, kKnobs[k].producer}) > 0;
                });
                if (used) params_.push_back({c, k});
            }
    }

    const CalibrateOptions& o_;
    PhysicsConfig config_;
    std::vector<FlightData> flights_;
    std::vector<Trial> trials_;
    std::vector<AloneFlight> alone_;
    std::vector<std::set<std::pair<std::size_t, bool>>> roles_;  // per flight
    std::vector<Param> params_;
};

namespace {

std::vector<std::size_t> flights_except(const Calibration& cal, std::optional<std::size_t> left_out) {
    std::vector<std::size_t> use;
    for (std::size_t f = 0; f < cal.flights().size(); ++f)
        if (!left_out || cal.flights()[f].trial != *left_out) use.push_back(f);
    return use;
}

double rmse(const Eigen::VectorXd& r) {
    return r.size() ? std::sqrt(r.squaredNorm() / static_cast<double>(r.size())) : 0;
}

// The forward-difference Jacobian of the residuals; a parameter that acts on none of the flights
// gets a zero column (and is left where it is).
Eigen::MatrixXd jacobian(const Calibration& cal, const std::vector<double>& x, const Eigen::VectorXd& r0,
                         const std::vector<std::size_t>& use, const std::vector<double>& start) {
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(r0.size(), static_cast<Eigen::Index>(x.size()));
    for (std::size_t p = 0; p < x.size(); ++p) {
        if (std::none_of(use.begin(), use.end(), [&](std::size_t f) { return cal.acts_on(p, f); })) continue;
        auto xp = x;
        const double h = kStepFraction * std::max(std::abs(x[p]), std::abs(start[p]) + kStepFloor);
        xp[p] += x[p] + h <= cal.knob(p).upper ? h : -h;
        J.col(static_cast<Eigen::Index>(p)) = (cal.residuals(xp, use, true) - r0) / (xp[p] - x[p]);
    }
    return J;
}

// Levenberg-Marquardt within the knobs' bounds, from x, on the flights in `use`.
std::vector<double> fit(const Calibration& cal, std::vector<double> x, const std::vector<std::size_t>& use,
                        int iterations, const CalibrateOptions& o, const std::string& what) {
    const auto start = cal.start();
    Eigen::VectorXd r = cal.residuals(x, use, true);
    double cost = r.squaredNorm(), lambda = kLambda0;
    if (o.progress) o.progress(log::cat(what, ": start, RMSE f_d ", rmse(r), " N"));
    for (int it = 0; it < iterations && lambda < kLambdaMax; ++it) {
        const Eigen::MatrixXd J = jacobian(cal, x, r, use, start);
        const Eigen::MatrixXd A = J.transpose() * J;
        const Eigen::VectorXd g = J.transpose() * r;
        bool improved = false;
        while (!improved && lambda < kLambdaMax) {
            Eigen::MatrixXd M = A;
            for (Eigen::Index k = 0; k < M.rows(); ++k)
                M(k, k) = A(k, k) > 0 ? A(k, k) * (1 + lambda) : kUnusedDiagonal;
            const Eigen::VectorXd step = M.ldlt().solve(-g);
            auto y = x;
            for (std::size_t p = 0; p < y.size(); ++p)
                y[p] = std::clamp(y[p] + step[static_cast<Eigen::Index>(p)], cal.knob(p).lower, cal.knob(p).upper);
            const Eigen::VectorXd ry = cal.residuals(y, use, true);
            if (ry.squaredNorm() < cost) {
                const double gain = (cost - ry.squaredNorm()) / cost;
                x = y, r = ry, cost = ry.squaredNorm(), lambda = std::max(lambda / 3, kLambdaMin), improved = true;
                if (gain < kRelativeTolerance) return x;
            } else {
                lambda *= 4;
            }
        }
        if (o.progress)
            o.progress(log::cat(what, ": iteration ", it + 1, ", RMSE f_d ", std::sqrt(cost / r.size()), " N"));
    }
    return x;
}

// A flight's near samples onto `s`: offset, height above, recorded f_d, and f_d as `p1` and `p0`
// predict it (the calibrated and the uncalibrated physics).
void add_rows(PairingSamples& s, const FlightData& fd, const std::vector<Wrench6>& p1, const std::vector<Wrench6>& p0) {
    for (std::size_t k = 0; k < fd.rows.size(); ++k) {
        const auto i = fd.rows[k];
        s.rows.push_back({fd.offset[k], fd.above[k], fd.sim->measured()[i][kFdAxis], p1[i][kFdAxis], p0[i][kFdAxis]});
    }
}

// Per pairing, every near sample (add_rows).
std::vector<PairingSamples> samples_by_pairing(const Calibration& cal, const std::vector<double>& x0,
                                               const std::vector<double>& x, const CalibrateOptions& o) {
    std::map<std::string, PairingSamples> by;
    const auto base = cal.config_of(x0), fitted = cal.config_of(x);
    for (const auto& fd : cal.flights()) {
        throw_if_stopped(o.stop, "the calibration");
        auto& s = by[fd.pairing];
        s.pairing = fd.pairing;
        add_rows(s, fd, fd.sim->recorded(fitted), fd.sim->recorded(base));
    }
    std::vector<PairingSamples> out;
    for (auto& [name, s] : by) out.push_back(std::move(s));
    return out;
}

// The jets' turbulence intensity the residual shows: half the slope 2I of its spread against the
// calibrated push, pooled over every pairing's near samples (0: the spread does not grow).
double turbulence_intensity(const std::vector<PairingSamples>& pairings) {
    PairingSamples all;
    for (const auto& p : pairings) all.rows.insert(all.rows.end(), p.rows.begin(), p.rows.end());
    return scatter_of(all).two_i / 2;
}

// A fold's: measured on the residual its own calibration `xt` leaves on its own flights (the
// trial it leaves out plays no part, as in its jets; the air along each flight is mostly still
// cached from the fit).
double fold_turbulence_intensity(const Calibration& cal, const std::vector<double>& xt,
                                 const std::vector<std::size_t>& flights, const CalibrateOptions& o) {
    PairingSamples all;
    const auto fitted = cal.config_of(xt);
    for (auto f : flights) {
        throw_if_stopped(o.stop, "the calibration");
        const auto& fd = cal.flights()[f];
        const auto p = fd.sim->recorded(fitted);
        add_rows(all, fd, p, p);
    }
    return scatter_of(all).two_i / 2;
}

// The base with the calibrated classes and turbulence, and the line that says where they came from.
PhysicsConfig with_provenance(const PhysicsConfig& fitted, const PhysicsConfig& base, double intensity,
                              const std::string& on) {
    PhysicsConfig c = base;
    c.classes = fitted.classes;
    if (intensity > 0) c.turbulence.enabled = true, c.turbulence.intensity = intensity;
    c.calibration = log::cat("dw-explain calibrate ", on, ", f_d where a neighbour is near");
    return c;
}

// A flight's quiet f_d: where nobody is near, and where a neighbour is but physics c predicts a
// push it calls quiet (physics::quiet_push: a neighbour below, or beside its jet).
std::vector<double> quiet_f_d(const FlightData& fd, const PhysicsConfig& c) {
    auto out = fd.far_f_d;
    const auto pred = fd.sim->recorded(c);
    for (auto i : fd.rows)
        if (physics::quiet_push(pred[i][kFdAxis])) out.push_back(fd.sim->measured()[i][kFdAxis]);
    return out;
}

// Each flight's own noise floor under physics c: its quiet f_d's spread where it has
// kMinFarSamples such samples, else NaN.
std::vector<double> own_floors(const Calibration& cal, const PhysicsConfig& c) {
    std::vector<double> out;
    for (const auto& f : cal.flights()) {
        const auto quiet = quiet_f_d(f, c);
        out.push_back(quiet.size() >= physics::kMinFarSamples ? standard_deviation(quiet) : NAN);
    }
    return out;
}

// Each vehicle class's noise floor as the sufferer (VehicleClass::noise_floor_n): the median of its
// flights' own floors (`own`) and of its flights alone.
void set_noise_floors(PhysicsConfig& c, const Calibration& cal, const std::vector<double>& own) {
    for (std::size_t k = 0; k < c.classes.size(); ++k) {
        std::vector<double> floors;
        for (std::size_t f = 0; f < cal.flights().size(); ++f)
            if (cal.flights()[f].sufferer_class == k && std::isfinite(own[f])) floors.push_back(own[f]);
        for (const auto& a : cal.alone())
            if (a.vehicle_class == c.classes[k].name) floors.push_back(a.sd_f_d);
        if (!floors.empty()) c.classes[k].noise_floor_n = median(floors);
    }
}

// Each flight's noise floor: its own (own_floors), else its sufferer class's (set_noise_floors), else
// — no flight of its class is ever quiet — the jitter of its whole recording (successive
// differences, as the predictor's intervals do: it leaves out the residual's slow error).
std::vector<double> flight_floors(const Calibration& cal, const PhysicsConfig& base, const std::vector<double>& own) {
    PhysicsConfig c = base;
    set_noise_floors(c, cal, own);
    std::vector<double> out;
    for (std::size_t i = 0; i < cal.flights().size(); ++i) {
        const auto& f = cal.flights()[i];
        double floor = std::isfinite(own[i]) ? own[i] : c.classes[f.sufferer_class].noise_floor_n;
        if (!(floor > 0)) {
            std::vector<double> f_d;
            for (const auto& w : f.sim->measured()) f_d.push_back(w[kFdAxis]);
            floor = sd_from_differences(f_d);
        }
        out.push_back(floor);
    }
    return out;
}

// The trial's flights explained against the calibration that left it out (reports under folds/<trial>/).
void explain_heldout(TrialError& e, const PhysicsConfig& fold, const CalibrateOptions& o) {
    const fs::path dir = fs::path(o.out_dir) / "folds" / e.trial;
    fs::create_directories(dir);
    write_file((dir / "physics.yaml").string(), physics::to_yaml(fold));
    for (const auto& folder : e.flights) {
        throw_if_stopped(o.stop, "the calibration");
        if (o.progress) o.progress(log::cat("explaining ", folder, " with the calibration without ", e.trial));
        ExplainOptions xo;
        xo.physics = fold;
        xo.stop = o.stop;
        const flight::Flight f = flight::read_flight(folder);
        const ExplainResult r = explain(f, xo);
        write_report(f, r, xo, (dir / fs::path(folder).filename()).string());
        e.explained_ratio.push_back(r.heldout_after[kFdAxis] / r.noise_floor[kFdAxis]);
        e.discrepancy_ratio.push_back(r.discrepancy.heldout_after[kFdAxis] / r.noise_floor[kFdAxis]);
        e.explained_by.emplace_back();
        for (const auto& c : r.accepted) e.explained_by.back().push_back(c.effect.name);
    }
}

}  // namespace

AloneFlight measure_alone(const flight::Flight& f, const std::string& dir, const std::string& vehicle_class) {
    const auto sufferer = flight::body_tracks(f, dir + "/").sufferer;
    AloneFlight a{fs::path(dir).filename().string(), vehicle_class};
    std::vector<double> y, v;
    for (const auto& w : f.wrench)
        if (w.t >= sufferer.t.front() && w.t <= sufferer.t.back() && std::isfinite(w.w[kFdAxis]) &&
            -sufferer.position_at(w.t)[2] >= kAloneMinHeight_m)
            y.push_back(w.w[kFdAxis]), v.push_back(sufferer.velocity_at(w.t)[2]);
    if (y.size() < 3)
        throw InputError(log::cat(dir, "/wrench.csv: fewer than 3 f_d samples while the sufferer flies alone at least ",
                                  kAloneMinHeight_m, " m above the floor"));
    Eigen::MatrixXd X(static_cast<Eigen::Index>(y.size()), 2);
    const Eigen::VectorXd Y = Eigen::Map<const Eigen::VectorXd>(y.data(), static_cast<Eigen::Index>(y.size()));
    X.col(0).setOnes();
    X.col(1) = Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
    const Eigen::Vector2d line = X.colPivHouseholderQr().solve(Y);
    a.samples = y.size();
    a.mean_f_d = Y.mean();
    a.rms_f_d = std::sqrt(Y.squaredNorm() / static_cast<double>(y.size()));
    a.sd_f_d = std::sqrt(std::max(0.0, a.rms_f_d * a.rms_f_d - a.mean_f_d * a.mean_f_d));
    a.slope_per_v_d = line[1];
    a.rms_after_line = std::sqrt((Y - X * line).squaredNorm() / static_cast<double>(y.size()));
    a.floor_differences = floor_from_differences(y);
    return a;
}

CalibrateResult calibrate(const CalibrateOptions& o) {
    const auto t0 = std::chrono::steady_clock::now();
    require_output_dir(o.out_dir, "--out");
    Calibration cal(o);
    StagedFolder staged(o.out_dir);  // the physics file, report, pictures and folds appear together, or none
    CalibrateOptions in = o;         // everything of the run is written into the staging folder
    in.out_dir = staged.path();
    CalibrateResult R;
    const auto x0 = cal.start();
    const auto x = fit(cal, x0, flights_except(cal, std::nullopt), o.max_iterations, o, "every trial");
    const auto pairings = samples_by_pairing(cal, x0, x, o);
    R.turbulence_intensity = turbulence_intensity(pairings);
    std::vector<std::vector<double>> replicates;
    const auto own_floor = own_floors(cal, cal.config_of(x));
    const auto floors = flight_floors(cal, cal.config_of(x), own_floor);
    for (std::size_t t = 0; t < cal.trials().size(); ++t) {
        const auto& trial = cal.trials()[t];
        const auto others = flights_except(cal, t);
        const auto xt = fit(cal, x, others, o.fold_iterations, o, "without " + trial.name);
        replicates.push_back(xt);
        const auto& own = trial.flights;
        TrialError e;
        e.trial = trial.name;
        for (auto f : own) e.flights.push_back(cal.flights()[f].dir), e.pairing = cal.flights()[f].pairing;
        const auto before = cal.residuals(x0, own, false);
        e.samples = static_cast<std::size_t>(before.size());
        e.rmse_before = rmse(before);
        e.rmse_all = rmse(cal.residuals(x, own, false));
        e.rmse_heldout = rmse(cal.residuals(xt, own, false));
        e.turbulence_intensity = fold_turbulence_intensity(cal, xt, others, o);
        e.noise = physics::fit_prediction_noise(cal.noise_samples(xt, others, true, floors));
        const NoiseScale noise{floors, e.noise};
        e.z_rms_heldout = rmse(cal.residuals(xt, own, false, &noise));
        if (o.explain_heldout)
            explain_heldout(
                e, with_provenance(cal.config_of(xt), o.physics, e.turbulence_intensity, "without " + trial.name), in);
        R.trials.push_back(e);
    }
    const auto sd = jackknife_sd(replicates);
    const double t = t975(static_cast<int>(replicates.size()) - 1);
    for (std::size_t p = 0; p < x.size(); ++p)
        R.parameters.push_back({cal.class_of(p), cal.knob(p).name, cal.knob(p).unit, x0[p], x[p],
                                std::max(x[p] - t * sd[p], cal.knob(p).lower),  // within the parameter's bounds
                                std::min(x[p] + t * sd[p], cal.knob(p).upper)});
    R.alone = cal.alone();
    R.calibrated =
        with_provenance(cal.config_of(x), o.physics, R.turbulence_intensity,
                        log::cat("on ", cal.flights().size(), " flights of ", cal.trials().size(), " trials"));
    set_noise_floors(R.calibrated, cal, own_floor);
    R.calibrated.prediction_noise =
        physics::fit_prediction_noise(cal.noise_samples(x, flights_except(cal, std::nullopt), true, floors));
    R.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    write_calibration(pairings, R, in);
    staged.commit();
    R.physics_path = (fs::path(o.out_dir) / kCalibratedPhysicsFile).string();
    R.report_path = (fs::path(o.out_dir) / kCalibrationReportFile).string();
    return R;
}

}  // namespace dw::analysis
