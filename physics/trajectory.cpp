#include "physics/trajectory.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::physics {

const std::vector<std::string>& formation_names() {
    static const std::vector<std::string> names{"single",           "side_by_side", "leader_follower",
                                                "leader_follower3", "stack",        "hybrid"};
    return names;
}

Formation make_formation(const std::string& name) {
    // Travel is along E: abreast means offset in N, in line means offset in E. Up is -D.
    if (name == "single") return {name, "single", {Vec3(0, 0, 0)}};
    if (name == "side_by_side") return {name, "side_by_side", {Vec3(-0.25, 0, 0), Vec3(0.25, 0, 0)}};
    if (name == "leader_follower") return {name, "leader_follower", {Vec3(0, 0.25, 0), Vec3(0, -0.25, 0)}};
    // K = 3 in line with 0.5 m offsets from the centroid (PHYSICS.md).
    if (name == "leader_follower3")
        return {name, "leader_follower", {Vec3(0, 0.5, 0), Vec3(0, 0, 0), Vec3(0, -0.5, 0)}};
    // The lower vehicle at the reference altitude flies in the upper one's downwash.
    if (name == "stack") return {name, "stack", {Vec3(0, 0.1, -0.5), Vec3(0, 0, 0)}};
    if (name == "hybrid") {  // equilateral triangle, 0.6 m sides, in one horizontal plane
        const double R = 0.6 / std::sqrt(3.0);
        return {name,
                "hybrid",
                {Vec3(R, 0, 0), Vec3(-R / 2, R * std::sqrt(3.0) / 2, 0), Vec3(-R / 2, -R * std::sqrt(3.0) / 2, 0)}};
    }
    throw InputError(log::cat("unknown formation '", name,
                              "' (expected single, side_by_side, leader_follower, leader_follower3, stack or hybrid)"));
}

void ReferenceTrajectory::add(Kind kind, double length_s, const Vec3& p0, const Vec3& p1, double speed) {
    Segment s{kind, duration_, length_s, p0, Vec3::Zero(), (p1 - p0).norm(), speed};
    if (s.distance > 1e-12) s.dir = (p1 - p0) / s.distance;
    segments_.push_back(s);
    duration_ += length_s;
}

ReferenceTrajectory::ReferenceTrajectory(const GridOptions& o) {
    require_in(o.legs, kLegsRange, "legs");
    if (o.altitudes_m.empty()) throw InputError("--altitudes needs at least one altitude");
    for (double a : o.altitudes_m) require_in(a, kAltitudeRange, "altitude above the sufferer");
    require_in(o.speed_mps, kSpeedRange, "leg speed");
    const double hw = o.half_width_m;
    const double ramp_m = 0.5 * o.speed_mps * o.ramp_s;  // distance of a cosine speed ramp
    const double far = hw + ramp_m;
    const int per_alt = o.lines_n_m.empty() ? (o.legs + static_cast<int>(o.altitudes_m.size()) - 1) /
                                                  static_cast<int>(o.altitudes_m.size())
                                            : static_cast<int>(o.lines_n_m.size());

    std::vector<LegInfo> plan;
    int direction = 1;
    for (std::size_t a = 0; a < o.altitudes_m.size(); ++a) {
        for (int k = 0; k < per_alt && static_cast<int>(plan.size()) < o.legs; ++k) {
            LegInfo leg;
            leg.index = static_cast<int>(plan.size());
            if (!o.lines_n_m.empty()) leg.n_m = o.lines_n_m[static_cast<std::size_t>(k)];
            else leg.n_m = per_alt == 1 ? 0.0 : -hw + 2.0 * hw * k / (per_alt - 1);
            leg.altitude_m = o.altitudes_m[a];
            leg.direction = direction;
            direction = -direction;
            plan.push_back(leg);
        }
    }
    auto start_of = [&](const LegInfo& l) { return Vec3(l.n_m, -l.direction * far, -o.stand_height_m - l.altitude_m); };
    auto end_of = [&](const LegInfo& l) { return Vec3(l.n_m, l.direction * far, -o.stand_height_m - l.altitude_m); };

    Vec3 here = start_of(plan.front());
    add(Kind::hold, o.start_hover_s, here, here, 0);
    for (std::size_t i = 0; i < plan.size(); ++i) {
        LegInfo& leg = plan[i];
        const Vec3 start = start_of(leg);
        if ((start - here).norm() > 1e-9) {
            // Minimum-jerk transition, peak speed 1.875 D / T kept at the leg speed.
            const double d = (start - here).norm();
            add(Kind::min_jerk, std::max(1.0, 1.875 * d / o.speed_mps), here, start, 0);
            add(Kind::hold, o.hover_s, start, start, 0);
        }
        const Vec3 a = start + Vec3(0, leg.direction * ramp_m, 0);
        const Vec3 b = a + Vec3(0, leg.direction * 2.0 * hw, 0);
        const Vec3 end = end_of(leg);
        add(Kind::ramp_up, o.ramp_s, start, a, o.speed_mps);
        leg.t_start = duration_;
        add(Kind::cruise, 2.0 * hw / o.speed_mps, a, b, o.speed_mps);
        leg.t_end = duration_;
        add(Kind::ramp_down, o.ramp_s, b, end, o.speed_mps);
        add(Kind::hold, o.hover_s, end, end, 0);
        here = end;
    }
    legs_ = std::move(plan);
}

Setpoint ReferenceTrajectory::at(double t) const {
    t = std::clamp(t, 0.0, duration_);
    auto it =
        std::upper_bound(segments_.begin(), segments_.end(), t, [](double v, const Segment& s) { return v < s.t0; });
    const Segment& s = *(it == segments_.begin() ? it : std::prev(it));
    const double T = s.length_s;
    const double tl = std::clamp(t - s.t0, 0.0, T);
    const double tau = T > 0 ? tl / T : 0.0;
    double pos = 0, vel = 0, acc = 0;
    switch (s.kind) {
        case Kind::hold: break;
        case Kind::min_jerk: {
            const double D = s.distance;
            pos = D * (10 * std::pow(tau, 3) - 15 * std::pow(tau, 4) + 6 * std::pow(tau, 5));
            vel = D / T * (30 * tau * tau - 60 * std::pow(tau, 3) + 30 * std::pow(tau, 4));
            acc = D / (T * T) * (60 * tau - 180 * tau * tau + 120 * std::pow(tau, 3));
            break;
        }
        case Kind::ramp_up:  // v = V/2 (1 - cos(pi tau))
            pos = 0.5 * s.speed * (tl - T / M_PI * std::sin(M_PI * tau));
            vel = 0.5 * s.speed * (1 - std::cos(M_PI * tau));
            acc = 0.5 * s.speed * M_PI / T * std::sin(M_PI * tau);
            break;
        case Kind::cruise:
            pos = s.speed * tl;
            vel = s.speed;
            break;
        case Kind::ramp_down:  // v = V/2 (1 + cos(pi tau))
            pos = 0.5 * s.speed * (tl + T / M_PI * std::sin(M_PI * tau));
            vel = 0.5 * s.speed * (1 + std::cos(M_PI * tau));
            acc = -0.5 * s.speed * M_PI / T * std::sin(M_PI * tau);
            break;
    }
    Setpoint sp;
    sp.position = s.p0 + pos * s.dir;
    sp.velocity = vel * s.dir;
    sp.acceleration = acc * s.dir;
    return sp;
}

}  // namespace dw::physics
