#include "importer/neural_swarm.hpp"

#include <zlib.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>

#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/shutdown.hpp"
#include "core/stats.hpp"
#include "core/text.hpp"
#include "flight/flight.hpp"

namespace dw::importer {
namespace {
namespace fs = std::filesystem;

constexpr double kG = 9.81;  // the authors' g for Fa and thrust_des
// The authors' onboard interaction network's prediction of Fa_z (kFazField): the reference.
constexpr const char* kFazSource =
    "the Neural-Swarm authors' onboard interaction network (ctrlFa.Faz, run on the vehicle in flight)";
constexpr double kTareDistance_m = 0.35;  // Fa is tared where every neighbour is farther than this
constexpr double kGap_s = 0.05;           // a longer pause between samples is reported
constexpr double kSteepTilt_rad = 30.0 * M_PI / 180.0;

const std::map<std::string, CrazyflieType>& types() {
    static const std::map<std::string, CrazyflieType> t = {
        {"small",
         {"small",
          0.032,
          0.046,
          0.0225,
          0.07,
          {11.093358483549203, -39.08104165843915, -9.525647087583181, 20.573302305476638, 38.42885066644033}}},
        {"large",
         {"large",
          0.067,
          0.060,
          0.033,
          0.085,
          {44.10386631845999, -122.51151800146272, -36.18484254283743, 53.10772568607133, 107.6819263349139}}},
    };
    return t;
}

}  // namespace

const CrazyflieType& crazyflie_type(const std::string& vehicle) {
    // cf50..cf52: Crazyflie 2.1; cf100..cf102: on a parrot frame (the collection's README).
    int id = -1;
    if (vehicle.rfind("cf", 0) == 0) std::from_chars(vehicle.data() + 2, vehicle.data() + vehicle.size(), id);
    if (id >= 50 && id <= 52) return types().at("small");
    if (id >= 100 && id <= 102) return types().at("large");
    throw InputError(
        log::cat("vehicle '", vehicle, "': not one the Neural-Swarm collection describes (cf50-cf52, cf100-cf102)"));
}

namespace {

double thrust_n(const CrazyflieType& type, const std::array<double, 4>& pwm, double vbat_v) {
    const auto& c = type.thrust_g;
    const double v = vbat_v / 4.2;
    double grams = 0;
    for (double p : pwm) grams += c[0] + c[1] * p + c[2] * v + c[3] * p * p + c[4] * v * p;
    return grams * kG / 1000.0;
}

// The body z axis in the world frame (third column of R) from a scalar-last quaternion.
std::array<double, 3> body_z(const std::array<double, 4>& q) {
    const double x = q[0], y = q[1], z = q[2], w = q[3];
    return {2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)};
}

std::array<double, 3> position_at(const VehicleLog& log, double t) {
    const auto it = std::lower_bound(log.t_s.begin(), log.t_s.end(), t);
    if (it == log.t_s.begin()) return log.position_m.front();
    if (it == log.t_s.end()) return log.position_m.back();
    const auto i = static_cast<std::size_t>(it - log.t_s.begin());
    const double a = (t - log.t_s[i - 1]) / (log.t_s[i] - log.t_s[i - 1]);
    std::array<double, 3> p{};
    for (std::size_t k = 0; k < 3; ++k)
        p[k] = log.position_m[i - 1][k] + a * (log.position_m[i][k] - log.position_m[i - 1][k]);
    return p;
}

void warn_about(const VehicleLog& log, const ImportOptions& o) {
    if (!o.warn) return;
    const auto& type = crazyflie_type(log.name);
    double worst_gap = 0, lowest = INFINITY, steepest = 0;
    std::size_t gaps = 0, touches = 0;
    for (std::size_t i = 0; i < log.t_s.size(); ++i) {
        if (i > 0 && log.t_s[i] - log.t_s[i - 1] > kGap_s)
            ++gaps, worst_gap = std::max(worst_gap, log.t_s[i] - log.t_s[i - 1]);
        if (log.position_m[i][2] < type.ground_z_m) ++touches;
        lowest = std::min(lowest, log.position_m[i][2]);
        steepest = std::max(steepest, std::acos(std::clamp(body_z(log.quat_xyzw[i])[2], -1.0, 1.0)));
    }
    if (gaps) o.warn(log::cat(log.file, ": ", gaps, " gap(s) in the log, the longest ", worst_gap, " s"));
    if (touches)
        o.warn(log::cat(log.file, ": ", touches, " sample(s) below z = ", type.ground_z_m, " m: touching the ground"));
    if (steepest > kSteepTilt_rad) o.warn(log::cat(log.file, ": tilts up to ", steepest * 180 / M_PI, " degrees"));
    if (log.damaged_blocks)
        o.warn(log::cat(log.file, ": ", log.damaged_blocks, " damaged block(s) skipped (checksum)"));
}

// What a flight may hold (flight::kForceRange), checked where a sample's force is derived: each
// input is in its own range, but together (full PWM at 100 V) they can make an absurd thrust.
double require_force(const VehicleLog& s, std::size_t i, const char* what, double v) {
    if (!flight::kForceRange.contains(v))
        throw InputError(log::cat(s.where(i), ": ", what, ": ", range_problem(v, flight::kForceRange)));
    return v;
}

// Fa = m a_imu − T_lag R e_z (world, z up), tared where no neighbour is near (a vehicle alone:
// over its whole flight). Returns the tare.
std::array<double, 3> residuals(const VehicleLog& s, const std::vector<const VehicleLog*>& others,
                                const ImportOptions& o, std::vector<std::array<double, 3>>& fa) {
    const auto& type = crazyflie_type(s.name);
    double lag = thrust_n(type, s.pwm.front(), s.vbat_v.front());
    std::array<std::vector<double>, 3> far;
    for (std::size_t i = 0; i < s.t_s.size(); ++i) {
        const auto ez = body_z(s.quat_xyzw[i]);
        std::array<double, 3> f{};
        for (std::size_t k = 0; k < 3; ++k) f[k] = type.mass_kg * s.accel_mps2[i][k] - lag * ez[k];
        for (const double v : f) require_force(s, i, "the residual force", v);
        const double thrust = thrust_n(type, s.pwm[i], s.vbat_v[i]);
        lag = o.thrust_lag * lag +
              (1 - o.thrust_lag) * require_force(s, i, "the thrust of its PWM and battery voltage", thrust);
        fa.push_back(f);
        bool alone = true;
        for (const auto& n : others) {
            const auto p = position_at(*n, s.t_s[i]);
            alone = alone && std::hypot(p[0] - s.position_m[i][0], p[1] - s.position_m[i][1]) > kTareDistance_m;
        }
        if (alone)
            for (std::size_t k = 0; k < 3; ++k) far[k].push_back(f[k]);
    }
    std::array<double, 3> tare{};
    if (far[0].size() < 20) {
        if (o.warn)
            o.warn(log::cat(s.file, ": fewer than 20 samples with every neighbour > ", kTareDistance_m,
                            " m away: Fa not tared"));
        return tare;
    }
    for (std::size_t k = 0; k < 3; ++k) tare[k] = median(far[k]);
    for (auto& f : fa)
        for (std::size_t k = 0; k < 3; ++k) f[k] -= tare[k];
    return tare;
}

// World z-up (x, y, z) -> NED (n, e, d): a half turn about x. Quaternions: (w, x, -y, -z).
std::array<double, 3> to_ned(const std::array<double, 3>& v) { return {v[0], -v[1], -v[2]}; }

// A log that is not two folders deep (at /, or in a folder at /).
constexpr const char* kUnknownCollection = "(unknown collection)";

nlohmann::json source_of(const std::vector<VehicleLog>& logs) {
    std::vector<std::string> files;
    nlohmann::json names = nlohmann::json::array();
    for (const auto& l : logs) {
        files.push_back(l.file);
        // <experiment>/<log>: a trial's logs are named alike across experiments (swap_ss/cf50_02 and
        // randomwalk_ss/cf50_02 are two trials).
        const fs::path p = fs::absolute(fs::path(l.file)).lexically_normal();
        names.push_back((p.parent_path().filename() / p.filename()).string());
    }
    return {{"collection", "aerorobotics/neural-swarm " + collection_of(files)}, {"logs", names}};
}

// The collection's readme: "do not use the Fa of cf100" (a Crazyflie 2.0, much worse IMU).
constexpr std::array<const char*, 1> kUnusableResidual{"cf100"};
constexpr const char* kUnusableResidualWhy = "a Crazyflie 2.0 with a much worse IMU, the collection's readme";
bool residual_usable(const std::string& vehicle) {
    return std::find(kUnusableResidual.begin(), kUnusableResidual.end(), vehicle) == kUnusableResidual.end();
}

// The onboard network's Fa_z as reference.csv's f_d (NED, newtons), where it ran: in older
// collections it is 0 throughout (the network was off), which is no prediction.
void add_reference(flight::Flight& f, const VehicleLog& s, const ImportOptions& o) {
    if (s.faz_g.empty()) return;
    if (std::all_of(s.faz_g.begin(), s.faz_g.end(), [](double g) { return g == 0.0; })) {
        if (o.warn)
            o.warn(log::cat(s.file, ": ", kFazField, " is 0 throughout (the onboard network was off): no reference"));
        return;
    }
    f.meta.reference = flight::ReferenceInfo{kFazSource, {"f_d"}};
    for (std::size_t i = 0; i < s.t_s.size(); ++i)
        f.reference.push_back({s.t_s[i], {NAN, NAN, -s.faz_g[i] * kG / 1000.0, NAN, NAN, NAN}});
}

flight::Flight to_flight(std::vector<VehicleLog> logs, const ImportOptions& o) {
    require_in(o.thrust_lag, kThrustLagRange, "the thrust lag");
    std::map<std::string, int> seen;
    for (const auto& l : logs) {
        if (seen[l.name]++) throw InputError(log::cat(l.file, ": a second log of ", l.name, " in one trial"));
        warn_about(l, o);
    }
    auto lowest = [](const VehicleLog& l) {
        std::vector<double> z;
        for (const auto& p : l.position_m) z.push_back(p[2]);
        return median(z);
    };
    std::string sufferer = o.sufferer;
    if (sufferer.empty()) {  // the lowest vehicle whose residual the authors trust
        const VehicleLog* best = nullptr;
        for (const auto& l : logs)
            if (residual_usable(l.name) && (!best || lowest(l) < lowest(*best))) best = &l;
        sufferer = (best ? *best : logs.front()).name;
    } else if (!residual_usable(sufferer) && o.warn) {
        o.warn(log::cat(sufferer, ": the authors say not to use this vehicle's residual (", kUnusableResidualWhy, ")"));
    }
    const auto it = std::find_if(logs.begin(), logs.end(), [&](const VehicleLog& l) { return l.name == sufferer; });
    if (it == logs.end()) throw InputError(log::cat("--sufferer: no log of '", sufferer, "' among the inputs"));
    std::vector<const VehicleLog*> others;
    for (const auto& l : logs)
        if (l.name != sufferer) others.push_back(&l);

    flight::Flight f;
    f.meta.sufferer = sufferer;
    f.meta.formation = "free";
    f.meta.stand_height_m.reset();
    f.meta.wrench_source = flight::WrenchSource::residual;
    f.meta.moments_measured = false;
    std::vector<std::array<double, 3>> fa;
    const auto tare = residuals(*it, others, o, fa);
    for (std::size_t i = 0; i < it->t_s.size(); ++i) {
        const auto ned = to_ned(fa[i]);
        f.wrench.push_back({it->t_s[i], {ned[0], ned[1], ned[2], 0, 0, 0}});
    }
    add_reference(f, *it, o);
    for (const auto& l : logs) {
        const auto& type = crazyflie_type(l.name);
        const std::uint16_t body = f.body_index(l.name);
        if (l.name != sufferer) f.meta.neighbours.push_back(l.name);
        f.meta.vehicles[l.name] = {type.mass_kg, 4, type.prop_radius_m,
                                   2 * type.arm_m};  // motor_distance_m: diagonal, motor to motor
        for (std::size_t i = 0; i < l.t_s.size(); ++i) {
            throw_if_stopped(o.stop, "the import");
            const auto& q = l.quat_xyzw[i];
            const double n = std::sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
            f.poses.push_back({l.t_s[i], body, to_ned(l.position_m[i]), {q[3] / n, q[0] / n, -q[1] / n, -q[2] / n}});
        }
    }
    std::stable_sort(f.poses.begin(), f.poses.end(),
                     [](const flight::PoseSample& a, const flight::PoseSample& b) { return a.t < b.t; });
    nlohmann::json battery = nlohmann::json::object();  // each vehicle's median battery voltage over the trial
    for (const auto& l : logs) battery[l.name] = median(l.vbat_v);
    f.meta.extra_json =
        nlohmann::json{
            {"source", source_of(logs)},
            {"residual",
             {{"definition",
               "Fa = m a_imu - T_lag R e_z (the authors' form; T_lag: T through a first-order lag, a = thrust_lag), "
               "NED"},
              {"thrust", "per motor c00 + c10 p + c01 v + c20 p^2 + c11 v p gram-force, p = PWM, v = Vbat/4.2"},
              {"thrust_lag", o.thrust_lag},
              {"tare_n", {to_ned(tare)[0], to_ned(tare)[1], to_ned(tare)[2]}},
              {"tare_rule", "median Fa where every neighbour is > 0.35 m away horizontally"}}},
            {"battery_v", battery},
            {"clocks",
             "each log from its own first sample; the logs of a trial taken as simultaneous (the authors' alignment)"}}
            .dump();
    return f;
}

class NeuralSwarm final : public Importer {
public:
    std::string_view name() const override { return "neural-swarm"; }
    std::string_view description() const override {
        return "Crazyflie logs of aerorobotics/neural-swarm (CSV or binary micro-SD logs), one file per vehicle of a "
               "trial";
    }
    flight::Flight import(const std::vector<std::string>& files, const ImportOptions& o) const override {
        std::vector<VehicleLog> logs;
        std::size_t samples = 0;
        for (const auto& file : files) {
            throw_if_stopped(o.stop, "the import");
            logs.push_back(read_neural_swarm_log(file, o.stop, kMaxTrialSamples - samples));
            samples += logs.back().t_s.size();
        }
        return to_flight(std::move(logs), o);
    }
};

}  // namespace

std::string collection_of(const std::vector<std::string>& log_files) {
    std::string found, first;
    for (const auto& file : log_files) {
        std::string c = fs::absolute(fs::path(file)).lexically_normal().parent_path().parent_path().filename().string();
        if (c.empty()) c = kUnknownCollection;
        if (first.empty()) {
            found = c;
            first = file;
        } else if (c != found) {
            throw InputError(log::cat("the logs of one trial come from two collections: ", first, " (", found, ") and ",
                                      file, " (", c, ")"));
        }
    }
    return found;
}

std::vector<CollectionTrial> collection_trials(const std::string& dir) {
    std::error_code ec;
    if (!fs::is_directory(input_status(dir, "collection")))
        throw InputError(log::cat(dir, ": not a folder of Neural-Swarm experiments"));
    std::map<std::string, std::map<std::string, fs::path>> trials;  // name -> vehicle -> log
    for (const auto& experiment : fs::directory_iterator(dir, ec)) {
        if (!experiment.is_directory(ec)) continue;
        for (const auto& file : fs::directory_iterator(experiment.path(), ec)) {
            const fs::path p = file.path();
            const std::string stem = p.stem().string();
            const auto cut = stem.find('_');
            if (!file.is_regular_file(ec) || cut == std::string::npos || (p.has_extension() && p.extension() != ".csv"))
                continue;
            auto& log = trials[experiment.path().filename().string() + stem.substr(cut)][stem.substr(0, cut)];
            if (log.empty() || !p.has_extension()) log = p;  // the binary log wins over the CSV made from it
        }
    }
    if (ec) throw InputError(log::cat(dir, ": ", ec.message()));
    std::vector<CollectionTrial> out;
    for (const auto& [name, logs] : trials) {
        out.push_back({name, {}});
        for (const auto& [vehicle, path] : logs) out.back().logs.push_back(path.string());
    }
    if (out.empty()) throw InputError(log::cat(dir, ": no Neural-Swarm trial (<experiment>/<vehicle>_<trial> logs)"));
    return out;
}

const Importer& neural_swarm_importer() {
    static const NeuralSwarm importer;
    return importer;
}

}  // namespace dw::importer
