#include "swarm_planner/plan.hpp"

#include <algorithm>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"

namespace dw::planner {

physics::Setpoint Plan::setpoint(std::size_t vehicle, double t) const {
    physics::Setpoint sp = reference.at(t);
    sp.position += formation.offsets[vehicle];
    return sp;
}

bool Geofence::contains(const physics::Vec3& x, double grow_m) const {
    return x.x() >= n_min - grow_m && x.x() <= n_max + grow_m && x.y() >= e_min - grow_m && x.y() <= e_max + grow_m &&
           x.z() >= d_min - grow_m && x.z() <= d_max + grow_m;
}

physics::Vec3 Geofence::on_floor(const physics::Vec3& x) const { return {x.x(), x.y(), std::min(x.z(), d_max)}; }

bool Geofence::holds_measured(const physics::Vec3& x) const {
    return x.z() <= d_max + kMeasuredBelowFloor_m && contains(on_floor(x), kTolerance_m);
}

Plan make_plan(const PlanOptions& o) {
    require_in(o.min_separation_m, kSeparationRange, "minimum separation");
    Plan p{o, physics::make_formation(o.formation), physics::ReferenceTrajectory(o.grid), {}};
    for (std::size_t i = 0; i < p.formation.offsets.size(); ++i) p.vehicles.push_back("v" + std::to_string(i + 1));
    return p;
}

namespace {
std::string where(const Plan& p, double t) {
    for (const auto& leg : p.reference.legs()) {
        if (t >= leg.t_start && t <= leg.t_end) return log::cat("on leg ", leg.index);
        if (t < leg.t_start) return log::cat("before leg ", leg.index);
    }
    return "after the last leg";
}
std::string fmt(const physics::Vec3& v) {
    char buf[96];
    std::snprintf(buf, sizeof(buf), "(%.2f, %.2f, %.2f)", v.x(), v.y(), v.z());
    return buf;
}
}  // namespace

std::optional<Violation> check(const Plan& p, const std::stop_token& stop) {
    const auto& f = p.options.fence;
    const physics::Vec3 sufferer(0, 0, -p.options.grid.stand_height_m);
    const std::size_t k = p.vehicles.size();
    const double duration = p.duration_s();
    if (!(std::isfinite(duration) && duration > 0))
        return Violation{0, log::cat("the plan's duration is ", duration, " s")};
    const auto steps = static_cast<long long>(std::ceil(duration / p.options.check_dt_s));
    std::vector<physics::Vec3> pos(k);
    for (long long step = 0; step <= steps; ++step) {
        if (step % 1000 == 0) throw_if_stopped(stop, "the plan's checks");
        const double t = std::min(duration, static_cast<double>(step) * p.options.check_dt_s);
        for (std::size_t i = 0; i < k; ++i) {
            const physics::Setpoint sp = p.setpoint(i, t);
            if (!is_finite(sp))
                return Violation{t, log::cat(p.vehicles[i], "'s setpoint is not finite at t = ", t, " s")};
            pos[i] = sp.position;
            const auto& x = pos[i];
            if (!f.contains(x, -f.margin_m)) {
                return Violation{t, log::cat(p.vehicles[i], " leaves the geofence at ", fmt(x), " m at t = ", t, " s (",
                                             where(p, t), "; fence N ", f.n_min, "..", f.n_max, ", E ", f.e_min, "..",
                                             f.e_max, ", D ", f.d_min, "..", f.d_max, " minus ", f.margin_m, " m)")};
            }
            const double to_stand = (x - sufferer).norm();
            if (!(to_stand >= p.options.min_separation_m)) {
                return Violation{t, log::cat(p.vehicles[i], " comes ", to_stand, " m from the sufferer at t = ", t,
                                             " s (", where(p, t), "); minimum ", p.options.min_separation_m, " m")};
            }
        }
        for (std::size_t a = 0; a < k; ++a) {
            for (std::size_t b = a + 1; b < k; ++b) {
                const double d = (pos[a] - pos[b]).norm();
                if (!(d >= p.options.min_separation_m)) {
                    return Violation{
                        t, log::cat(p.vehicles[a], " and ", p.vehicles[b], " come ", d, " m apart at t = ", t, " s (",
                                    where(p, t), "); minimum ", p.options.min_separation_m, " m")};
                }
            }
        }
    }
    return std::nullopt;
}

double coverage(const Plan& p, const std::stop_token& stop) {
    const double hw = p.options.grid.half_width_m, cell = 0.1;
    const int n = static_cast<int>(std::round(2 * hw / cell));
    std::vector<bool> covered(static_cast<std::size_t>(n * n), false);
    for (const auto& leg : p.reference.legs()) {
        throw_if_stopped(stop, "the plan's coverage");
        for (double t = leg.t_start; t <= leg.t_end; t += 0.02) {
            for (std::size_t v = 0; v < p.vehicles.size(); ++v) {
                const auto x = p.setpoint(v, t).position;
                for (int i = 0; i < n; ++i) {
                    const double cn = -hw + (i + 0.5) * cell;
                    if (std::abs(cn - x.x()) > cell) continue;
                    for (int j = 0; j < n; ++j) {
                        const double ce = -hw + (j + 0.5) * cell;
                        if (std::hypot(cn - x.x(), ce - x.y()) <= cell)
                            covered[static_cast<std::size_t>(i * n + j)] = true;
                    }
                }
            }
        }
    }
    return static_cast<double>(std::count(covered.begin(), covered.end(), true)) / static_cast<double>(covered.size());
}

std::string to_document(const Plan& p, bool json) {
    nlohmann::json j;
    j["format"] = "downwash-plan/1";
    j["formation"] = p.formation.name;
    j["speed_mps"] = p.options.grid.speed_mps;
    j["min_separation_m"] = p.options.min_separation_m;
    j["duration_s"] = p.duration_s();
    j["stand_height_m"] = p.options.grid.stand_height_m;
    j["vehicles"] = nlohmann::json::array();
    for (std::size_t i = 0; i < p.vehicles.size(); ++i) {
        const auto& o = p.formation.offsets[i];
        j["vehicles"].push_back({{"id", p.vehicles[i]}, {"offset_m", {o.x(), o.y(), o.z()}}});
    }
    j["legs"] = nlohmann::json::array();
    for (const auto& leg : p.reference.legs()) {
        const auto a = p.reference.at(leg.t_start).position, b = p.reference.at(leg.t_end).position;
        j["legs"].push_back({{"index", leg.index},
                             {"relative_altitude_m", leg.altitude_m},
                             {"direction", leg.direction > 0 ? "+E" : "-E"},
                             {"start_m", {a.x(), a.y(), a.z()}},
                             {"end_m", {b.x(), b.y(), b.z()}},
                             {"t_start_s", leg.t_start},
                             {"t_end_s", leg.t_end}});
    }
    if (json) return j.dump(2) + "\n";
    YAML::Emitter out;
    out.SetDoublePrecision(6);
    std::function<void(const nlohmann::json&)> emit = [&](const nlohmann::json& v) {
        if (v.is_object()) {
            out << YAML::BeginMap;
            for (const auto& [k, x] : v.items()) {
                out << YAML::Key << k << YAML::Value;
                emit(x);
            }
            out << YAML::EndMap;
        } else if (v.is_array()) {
            const bool flat = !v.empty() && v[0].is_number();
            if (flat) out << YAML::Flow;
            out << YAML::BeginSeq;
            for (const auto& x : v) emit(x);
            out << YAML::EndSeq;
        } else if (v.is_string()) {
            out << v.get<std::string>();
        } else if (v.is_number_integer()) {
            out << v.get<long long>();
        } else if (v.is_number()) {
            out << v.get<double>();
        } else if (v.is_boolean()) {
            out << v.get<bool>();
        }
    };
    emit(j);
    return std::string(out.c_str()) + "\n";
}

}  // namespace dw::planner
