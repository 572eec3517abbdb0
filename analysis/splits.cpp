#include "analysis/splits.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include "analysis/noise.hpp"
#include "analysis/score.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

namespace {

using Rows = std::vector<std::size_t>;

// Sample i's place along axis a.
double key_of(SplitAxis a, const ExplainData& d, const std::vector<Wrench6>& with, std::size_t i) {
    const auto& s = d.info[i];
    switch (a) {
        case SplitAxis::time: return d.sim.stamps()[i];
        case SplitAxis::height: return s.h;
        case SplitAxis::separation: return s.offset;
        case SplitAxis::direction: return s.direction;
        case SplitAxis::company: return s.shared;
        case SplitAxis::push: break;
    }
    double push = 0;  // the model's predicted wrench, in noise floors
    for (std::size_t k = 0; k < 6; ++k)
        if (d.sim.measured_axes()[k]) push += std::pow(with[i][k] / d.sigma[k], 2);
    return std::sqrt(push);
}

Rows near_samples(const ExplainData& d) {
    Rows near;
    for (auto i : d.on_legs)
        if (d.info[i].near) near.push_back(i);
    return near;
}

// The two parts of the near samples along axis a: the lowest and the highest third (the two
// directions of travel), or nothing when the flight does not span the axis.
std::optional<std::array<Rows, 2>> parts_along(const SplitAxisInfo& a, const ExplainData& d,
                                               const std::vector<Wrench6>& with, const Rows& near) {
    std::array<Rows, 2> parts;
    if (a.axis == SplitAxis::direction) {
        for (auto i : near)
            if (d.info[i].direction != 0) parts[d.info[i].direction > 0 ? 1 : 0].push_back(i);
    } else {
        std::vector<double> k;
        Rows rows;
        for (auto i : near) {
            // The push, and how it is shared, only where the model predicts one.
            const bool of_the_push = a.axis == SplitAxis::push || a.axis == SplitAxis::company;
            if (of_the_push && key_of(SplitAxis::push, d, with, i) < kMeasurablePush) continue;
            const double x = key_of(a.axis, d, with, i);
            k.push_back(x), rows.push_back(i);
        }
        if (k.size() < 2 * kMinPartSamples) return std::nullopt;
        std::vector<double> sorted = k;
        std::sort(sorted.begin(), sorted.end());
        const double low = sorted[sorted.size() / 3], high = sorted[2 * sorted.size() / 3];
        if (a.ratio_rule && !(high >= kSpanRatio * low)) return std::nullopt;
        if (a.axis == SplitAxis::company && high < kMinSharedSpan) return std::nullopt;
        for (std::size_t r = 0; r < rows.size(); ++r) {
            if (k[r] < low) parts[0].push_back(rows[r]);
            if (k[r] >= high) parts[1].push_back(rows[r]);
        }
    }
    if (parts[0].size() < kMinPartSamples || parts[1].size() < kMinPartSamples) return std::nullopt;
    return parts;
}

// The effect linearised at the whole flight's fit: each sample's residual in noise floors, its
// derivative in each parameter, and the Huber weight of the whole fit (IRLS).
struct Linearised {
    std::vector<Wrench6> residual, weight;
    std::vector<std::vector<Wrench6>> jacobian;  // per parameter
};

// The weights are the noise's: the floor and the turbulence that grows with the push (analysis/
// noise.hpp's excess), times the Huber weight of the residual in those units.
Linearised linearise(const ExplainData& d, Fit& fit, const Effect& e, const std::vector<double>& v,
                     const physics::PredictionNoise& noise) {
    Linearised L;
    const auto with = fit.predict(v);
    const PushNoise push(d, with, noise);
    const std::size_t n = with.size();
    L.residual.assign(n, Wrench6{});
    L.weight.assign(n, Wrench6{});
    for (std::size_t i = 0; i < n; ++i)
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            const double r = (d.sim.measured()[i][a] - with[i][a]) / d.sigma[a];
            const double var = 1 + push.relative(i, a), u = std::abs(r) / std::sqrt(var);
            L.residual[i][a] = r;
            L.weight[i][a] = (u <= d.huber_delta ? 1.0 : d.huber_delta / u) / var;
        }
    for (std::size_t p = 0; p < v.size(); ++p) {
        const double h = kSensitivityStep * (e.params[p].fit_max - e.params[p].fit_min);
        auto moved = v;
        moved[p] = v[p] + h <= e.params[p].fit_max ? v[p] + h : v[p] - h;
        const double step = moved[p] - v[p];
        const auto& pm = fit.predict(moved);
        std::vector<Wrench6> j(n, Wrench6{});
        for (std::size_t i = 0; i < n; ++i)
            for (std::size_t a = 0; a < 6; ++a)
                if (d.sim.measured_axes()[a]) j[i][a] = (pm[i][a] - with[i][a]) / step / d.sigma[a];
        L.jacobian.push_back(std::move(j));
    }
    return L;
}

// A part's weighted normal equations, per jackknife group: the Gauss-Newton step from the whole
// fit is (Σ A)⁻¹ Σ b over the groups kept.
struct Normal {
    Eigen::MatrixXd A;
    Eigen::VectorXd b;
};
using Normals = std::map<int, Normal>;

Normals normals_of(const ExplainData& d, const Linearised& L, const Rows& rows) {
    const auto P = static_cast<Eigen::Index>(L.jacobian.size());
    Normals out;
    for (auto i : rows) {
        auto& N = out[d.info[i].leg % kSplitGroups];
        if (N.A.size() == 0) N.A = Eigen::MatrixXd::Zero(P, P), N.b = Eigen::VectorXd::Zero(P);
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            Eigen::VectorXd j(P);
            for (Eigen::Index p = 0; p < P; ++p) j(p) = L.jacobian[static_cast<std::size_t>(p)][i][a];
            N.A += L.weight[i][a] * j * j.transpose();
            N.b += L.weight[i][a] * L.residual[i][a] * j;
        }
    }
    return out;
}

Eigen::VectorXd step_without(const Normals& N, int left_out) {
    Eigen::MatrixXd A;
    Eigen::VectorXd b;
    for (const auto& [g, n] : N) {
        if (g == left_out) continue;
        if (A.size() == 0) A = n.A, b = n.b;
        else A += n.A, b += n.b;
    }
    return A.ldlt().solve(b);
}

// Whether the effect moves the prediction, on these rows, by at least kEvidenceChange noise floors (RMS).
bool acts_on(const ExplainData& d, const Linearised& L, const std::vector<double>& range_step, const Rows& rows) {
    double s = 0, n = 0;
    for (auto i : rows)
        for (std::size_t a = 0; a < 6; ++a) {
            if (!d.sim.measured_axes()[a]) continue;
            double change = 0;
            for (std::size_t p = 0; p < L.jacobian.size(); ++p) change += L.jacobian[p][i][a] * range_step[p];
            s += change * change, n += 1;
        }
    return n > 0 && s / n >= kEvidenceChange * kEvidenceChange;
}

// One axis tested: per parameter, the low-minus-high difference and its jackknife z.
struct AxisTest {
    std::array<Rows, 2> parts;
    std::vector<double> low, high, z;
    int groups = 0;
};

std::optional<AxisTest> test_axis(const ExplainData& d, const Linearised& L, const std::vector<double>& v,
                                  std::array<Rows, 2> parts) {
    std::array<Normals, 2> N{normals_of(d, L, parts[0]), normals_of(d, L, parts[1])};
    std::set<int> groups;
    for (const auto& n : N)
        for (const auto& [g, x] : n) groups.insert(g);
    if (groups.size() < 3) return std::nullopt;  // a short flight has fewer blocks than kSplitGroups
    auto difference = [&](int left_out) {
        return Eigen::VectorXd(step_without(N[0], left_out) - step_without(N[1], left_out));
    };
    const Eigen::VectorXd all = difference(-1);
    std::vector<std::vector<double>> jack;
    for (int g : groups) {
        const Eigen::VectorXd x = difference(g);
        jack.emplace_back(x.data(), x.data() + x.size());
    }
    const auto sd = jackknife_sd(jack);
    AxisTest t{std::move(parts), {}, {}, {}, static_cast<int>(groups.size())};
    const Eigen::VectorXd lo = step_without(N[0], -1), hi = step_without(N[1], -1);
    for (std::size_t p = 0; p < v.size(); ++p) {
        const auto k = static_cast<Eigen::Index>(p);
        t.low.push_back(v[p] + lo(k));
        t.high.push_back(v[p] + hi(k));
        const double z = std::abs(all(k)) / sd[p];
        t.z.push_back(std::isfinite(z) ? z : 0.0);
    }
    return t;
}

std::string moved_note(const SplitMove& m, const SplitAxisInfo& a) {
    const bool grows = m.high > m.low;
    return log::cat("; but ", m.param, " ", grows ? "grows" : "falls", " from ", fixed(m.low, 3), " ", a.low, " to ",
                    fixed(m.high, 3), " ", a.high, " (", a.name, ": z = ", std::round(m.z * 10) / 10, ", beyond the ",
                    std::round(m.threshold * 10) / 10, " that ", m.tested, " splits at a family-wise ",
                    kSplitAlpha * 100,
                    " % allow): one value does not fit the flight, so the effect stands in for something else — not "
                    "accepted");
}

std::string kept_note(const SplitMove& m, const SplitAxisInfo& a) {
    return log::cat("; one value along every axis the flight spans (", m.tested, " splits): it moves most along ",
                    a.name, " (z = ", std::round(m.z * 10) / 10, "; refused above ", std::round(m.threshold * 10) / 10,
                    ")");
}

}  // namespace

const SplitAxisInfo& split_info(SplitAxis a) {
    return *std::find_if(kSplitAxes.begin(), kSplitAxes.end(), [a](const SplitAxisInfo& x) { return x.axis == a; });
}

OneJetPart one_jet_part(const ExplainData& d, const std::vector<Wrench6>& with) {
    OneJetPart out;
    std::vector<double> shares;
    for (auto i : near_samples(d)) {
        if (key_of(SplitAxis::push, d, with, i) < kMeasurablePush) continue;
        shares.push_back(d.info[i].shared);
        if (d.info[i].shared < kOneJetShare) ++out.alone;
    }
    out.measured = shares.size();
    if (!shares.empty()) out.median_share = median(shares);
    return out;
}

std::optional<SplitMove> one_value_check(const ExplainData& d, const physics::PhysicsConfig& current, const Effect& e,
                                         const std::vector<double>& values, double factor) {
    const Rows near = near_samples(d);
    if (near.size() < 2 * kMinPartSamples) return std::nullopt;
    Fit fit(d, current, e);
    const Linearised L = linearise(d, fit, e, values, physics::prediction_noise_of(current));
    const auto& with = fit.predict(values);
    std::vector<double> range_step;  // how far the effect is from absent, per parameter
    for (std::size_t p = 0; p < values.size(); ++p) range_step.push_back(values[p] - e.params[p].start);
    std::vector<std::pair<const SplitAxisInfo*, AxisTest>> tests;
    for (const auto& a : kSplitAxes) {
        auto parts = parts_along(a, d, with, near);
        // An effect that acts only on some parts (jet merging needs widened jets) cannot be measured
        // where it does not act: nothing to compare.
        if (!parts || !acts_on(d, L, range_step, (*parts)[0]) || !acts_on(d, L, range_step, (*parts)[1])) continue;
        if (auto t = test_axis(d, L, values, std::move(*parts))) tests.emplace_back(&a, std::move(*t));
    }
    if (tests.empty()) return std::nullopt;
    SplitMove m;
    m.tested = static_cast<int>(tests.size() * values.size());
    const SplitAxisInfo* where = nullptr;
    const AxisTest* best = nullptr;
    for (const auto& [a, t] : tests)
        for (std::size_t p = 0; p < values.size(); ++p) {
            const double threshold = t_two_sided(kSplitAlpha / m.tested, t.groups - 1);
            if (best && t.z[p] / threshold <= m.z / m.threshold) continue;
            where = a, best = &t;
            m = {a->axis, e.params[p].name, t.low[p], t.high[p], t.z[p], threshold, m.tested, t.z[p] > threshold, {}};
        }
    if (m.moved) {  // the report's numbers: the two parts fitted in full
        const auto p = static_cast<std::size_t>(
            std::find_if(e.params.begin(), e.params.end(), [&](const Parameter& x) { return x.name == m.param; }) -
            e.params.begin());
        Fit part(d, current, e);
        m.low = part.solve(values, best->parts[0], false, factor).first[p];
        m.high = part.solve(values, best->parts[1], false, factor).first[p];
    }
    m.note = m.moved ? moved_note(m, *where) : kept_note(m, *where);
    return m;
}

}  // namespace dw::analysis
