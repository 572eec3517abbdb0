#include "flight/blocks.hpp"

#include <algorithm>
#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::flight {

std::array<double, 3> Track::position_at(double time) const {
    if (t.empty()) return {0, 0, 0};
    if (time <= t.front()) return p.front();
    if (time >= t.back()) return p.back();
    const auto it = std::upper_bound(t.begin(), t.end(), time);
    const std::size_t i = static_cast<std::size_t>(it - t.begin());
    const double a = (time - t[i - 1]) / (t[i] - t[i - 1]);
    return {p[i - 1][0] + a * (p[i][0] - p[i - 1][0]), p[i - 1][1] + a * (p[i][1] - p[i - 1][1]),
            p[i - 1][2] + a * (p[i][2] - p[i - 1][2])};
}

std::array<double, 3> Track::velocity_at(double time, double h) const {
    const auto a = position_at(time - h), b = position_at(time + h);
    return {(b[0] - a[0]) / (2 * h), (b[1] - a[1]) / (2 * h), (b[2] - a[2]) / (2 * h)};
}

std::vector<Track> tracks(const Flight& f) {
    std::vector<Track> out(f.bodies.size());
    for (const auto& s : f.poses) {
        auto& tr = out[s.body];
        tr.t.push_back(s.t);
        tr.p.push_back(s.p);
        tr.q.push_back(s.q);
    }
    return out;
}

BodyTracks body_tracks(const Flight& f, const std::string& where) {
    auto all = tracks(f);
    const int sufferer = f.find_body(f.meta.sufferer);
    if (sufferer < 0 || all[static_cast<std::size_t>(sufferer)].t.empty())
        throw InputError(log::cat(where, "poses.csv: the sufferer '", f.meta.sufferer, "' (meta.json) has no poses"));
    BodyTracks out;
    out.sufferer = all[static_cast<std::size_t>(sufferer)];
    for (const auto& n : f.meta.neighbours) {
        const int b = f.find_body(n);
        if (b < 0 || all[static_cast<std::size_t>(b)].t.size() < 2)
            throw InputError(log::cat(where, "poses.csv: the neighbour '", n, "' (meta.json) has no poses"));
        out.neighbours.push_back(all[static_cast<std::size_t>(b)]);
    }
    return out;
}

const Leg* BlockCursor::at(double t) {
    while (i_ < blocks_.size() && blocks_[i_].t_end < t) ++i_;
    if (i_ < blocks_.size() && t >= blocks_[i_].t_start && t <= blocks_[i_].t_end) return &blocks_[i_];
    return nullptr;
}

namespace {
std::array<double, 3> centroid_at(const std::vector<const Track*>& ts, double t) {
    std::array<double, 3> c{0, 0, 0};
    for (const auto* tr : ts) {
        const auto p = tr->position_at(t);
        for (std::size_t a = 0; a < 3; ++a) c[a] += p[a] / static_cast<double>(ts.size());
    }
    return c;
}
}  // namespace

std::vector<Leg> find_legs(const Flight& f) {
    const auto trs = tracks(f);
    std::vector<const Track*> ns;
    for (const auto& name : f.meta.neighbours) {
        const int b = f.find_body(name);
        if (b >= 0 && !trs[static_cast<std::size_t>(b)].t.empty()) ns.push_back(&trs[static_cast<std::size_t>(b)]);
    }
    std::vector<Leg> legs;
    if (ns.empty()) return legs;
    const double t0 = ns.front()->t.front(), t1 = ns.front()->t.back();
    constexpr double dt = 0.05, h = 0.1;
    double start = -1;
    std::array<double, 3> dir{0, 0, 0};
    auto close = [&](double t) {
        if (start >= 0 && t - start >= 2.0) legs.push_back({static_cast<int>(legs.size()), start, t});
        start = -1;
    };
    for (double t = t0 + h; t < t1 - h; t += dt) {
        const auto a = centroid_at(ns, t - h), b = centroid_at(ns, t + h);
        const std::array<double, 3> v{(b[0] - a[0]) / (2 * h), (b[1] - a[1]) / (2 * h), (b[2] - a[2]) / (2 * h)};
        const double speed = std::hypot(v[0], v[1]);
        const bool moving = speed > 0.25 && std::abs(v[2]) < 0.1;
        if (moving && start >= 0) {  // the same leg only while heading and speed hold
            const double cosang = (v[0] * dir[0] + v[1] * dir[1]) / speed;
            if (cosang < 0.98 || std::abs(speed - dir[2]) > 0.15 * dir[2]) close(t);
        }
        if (moving && start < 0) {
            start = t;
            dir = {v[0] / speed, v[1] / speed, speed};
        }
        if (!moving) close(t);
    }
    close(t1);
    return legs;
}

const char* to_string(BlockKind k) {
    switch (k) {
        case BlockKind::legs: return "legs";
        case BlockKind::encounters: return "encounters";
        case BlockKind::time: return "time";
    }
    return "?";
}

namespace {

// The times of closest approach: per stretch where some neighbour is within its radius of the
// sufferer horizontally, the moment the (radius-normalised) distance is smallest.
std::vector<double> closest_approaches(const Flight& f, const std::vector<double>& radius, double t0, double t1) {
    const auto trs = tracks(f);
    const Track& suf = trs[static_cast<std::size_t>(f.find_body(f.meta.sufferer))];
    std::vector<std::pair<const Track*, double>> ns;
    for (std::size_t j = 0; j < f.meta.neighbours.size() && j < radius.size(); ++j) {
        const int b = f.find_body(f.meta.neighbours[j]);
        if (b >= 0 && !trs[static_cast<std::size_t>(b)].t.empty())
            ns.emplace_back(&trs[static_cast<std::size_t>(b)], radius[j]);
    }
    std::vector<double> out;
    constexpr double dt = 0.02;
    double best = INFINITY, best_t = 0;
    for (double t = t0; t <= t1; t += dt) {
        const auto s = suf.position_at(t);
        double d = INFINITY;
        for (const auto& [tr, r] : ns) {
            const auto p = tr->position_at(t);
            d = std::min(d, std::hypot(p[0] - s[0], p[1] - s[1]) / r);
        }
        if (d < 1 && d < best) best = d, best_t = t;
        if (d >= 1 && std::isfinite(best)) {
            out.push_back(best_t);
            best = INFINITY;
        }
    }
    if (std::isfinite(best)) out.push_back(best_t);
    return out;
}

}  // namespace

Blocks find_blocks(const Flight& f, int min_blocks, const std::vector<double>& encounter_radius_m) {
    Blocks b;
    b.blocks = f.legs ? *f.legs : find_legs(f);
    if (b.blocks.size() >= static_cast<std::size_t>(min_blocks)) return b;
    b.blocks.clear();
    const int suf = f.find_body(f.meta.sufferer);
    if (suf < 0 || f.poses.empty()) return b;
    double t0 = INFINITY, t1 = -INFINITY;
    for (const auto& p : f.poses)
        if (p.body == suf) t0 = std::min(t0, p.t), t1 = std::max(t1, p.t);
    if (!(t1 > t0)) return b;
    const auto peaks = closest_approaches(f, encounter_radius_m, t0, t1);
    if (peaks.size() >= static_cast<std::size_t>(min_blocks)) {
        b.kind = BlockKind::encounters;
        for (std::size_t k = 0; k < peaks.size(); ++k) {
            const double a = k == 0 ? t0 : 0.5 * (peaks[k - 1] + peaks[k]);
            const double e = k + 1 == peaks.size() ? t1 : 0.5 * (peaks[k] + peaks[k + 1]);
            b.blocks.push_back({static_cast<int>(k), a, e});
        }
        return b;
    }
    b.kind = BlockKind::time;
    const int n = std::max(2 * min_blocks, static_cast<int>(std::ceil((t1 - t0) / kTimeBlock_s)));
    for (int k = 0; k < n; ++k) b.blocks.push_back({k, t0 + (t1 - t0) * k / n, t0 + (t1 - t0) * (k + 1) / n});
    return b;
}

}  // namespace dw::flight
