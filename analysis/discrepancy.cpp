#include "analysis/discrepancy.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>

#include "analysis/noise.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

constexpr int kBumps = kOffsetBumps * kHeightBumps;
constexpr int kOwn = 6;                 // the sufferer's velocity and acceleration (n, e, d)
constexpr double kDifference_s = 0.02;  // the acceleration: velocities this far apart
constexpr double kHeightQuantiles[2] = {0.05, 0.95};

// Where each group's columns are: [start, start + count), in kInputGroups' order.
struct Layout {
    std::array<int, kInputGroups.size()> start{}, count{};
    int columns = 0;
    int at(InputGroup g) const { return start[static_cast<std::size_t>(g)]; }
};

Layout layout_of(int drift_bumps) {
    Layout l;
    const std::array<int, kInputGroups.size()> counts{
        1, 3 * kBumps, kOwn, drift_bumps + 6 * kGainDriftPowers, 6, 6 * kPushPowers, 6, 6, 6};
    for (std::size_t g = 0; g < counts.size(); ++g)
        l.start[g] = l.columns, l.count[g] = counts[g], l.columns += counts[g];
    return l;
}

// The bumps' heights: evenly between the near samples' height quantiles (all samples' when none is near).
struct Heights {
    double lo = 0, step = 0, width = kMinHeightWidth_m;
};

Heights heights_of(const ExplainData& d) {
    std::vector<double> near, all;
    for (auto i : d.on_legs) {
        const auto s = d.sim.sufferer(d.sim.stamps()[i]);
        for (int j = 0; j < d.sim.neighbours(); ++j) {
            const double above = s[2] - d.sim.position(j, d.sim.stamps()[i])[2];
            all.push_back(above);
            if (d.info[i].near) near.push_back(above);
        }
    }
    auto& v = near.empty() ? all : near;
    if (v.empty()) return {};
    std::sort(v.begin(), v.end());
    const auto at = [&](double q) { return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))]; };
    Heights h;
    h.lo = at(kHeightQuantiles[0]);
    h.step = (at(kHeightQuantiles[1]) - h.lo) / (kHeightBumps - 1);
    h.width = std::max(h.step, kMinHeightWidth_m);
    return h;
}

double bump(double x, double centre, double width) { return std::exp(-0.5 * std::pow((x - centre) / width, 2)); }

// The drift's bumps over the flight's time: from its first sample on a block to its last.
struct Drift {
    double t0 = 0, t1 = 0;
    int count = 0;
};

Drift drift_of(const ExplainData& d) {
    if (d.on_legs.empty()) return {};
    const double t0 = d.sim.stamps()[d.on_legs.front()], t1 = d.sim.stamps()[d.on_legs.back()];
    return {t0, t1, static_cast<int>(std::floor((t1 - t0) / kDriftSpacing_s)) + 2};
}

// The model's prediction at sample i in noise floors: its norm, the push.
double push_of(const Resimulation& sim, const AxisValues& sigma, const std::vector<Wrench6>& pred, std::size_t i) {
    double s = 0;
    for (std::size_t a = 0; a < 6; ++a)
        if (sim.measured_axes()[a]) s += std::pow(pred[i][a] / sigma[a], 2);
    return std::sqrt(s);
}

// The push that counts as 1: the near samples' kPushQuantile of the norm.
double push_top(const ExplainData& d, const std::vector<Wrench6>& pred) {
    std::vector<double> v;
    for (auto i : d.on_legs)
        if (d.info[i].near) v.push_back(push_of(d.sim, d.sigma, pred, i));
    if (v.empty()) return 1;
    std::sort(v.begin(), v.end());
    return std::max(v[static_cast<std::size_t>(kPushQuantile * static_cast<double>(v.size() - 1))], 1e-9);
}

// The frame the inputs are measured in: learnt from one flight, kept with the discrepancy so that
// it means the same on another (physics::LearntDiscrepancy).
struct Frame {
    Heights h;
    Drift drift;
    double top = 1;
    AxisValues sigma{};
};

Frame frame_of(const ExplainData& d, const std::vector<Wrench6>& pred) {
    return {heights_of(d), drift_of(d), push_top(d, pred), d.sigma};
}

Frame frame_of(const physics::LearntDiscrepancy& m) {
    return {{m.height_lo_m, m.height_step_m, m.height_width_m}, {m.t0_s, m.t1_s, m.drift_bumps}, m.push_top, m.sigma};
}

struct Context {
    const Resimulation& sim;
    const std::vector<SampleInfo>& info;
    const std::vector<Wrench6>& pred;
    Frame f;
    Layout layout;
};

void geometry_inputs(const Context& c, std::size_t i, Eigen::RowVectorXd& row) {
    const auto& sim = c.sim;
    const double t = sim.stamps()[i];
    const auto s = sim.sufferer(t);
    const int g = c.layout.at(InputGroup::geometry);
    for (int j = 0; j < sim.neighbours(); ++j) {
        const auto p = sim.position(j, t);
        const double dn = p[0] - s[0], de = p[1] - s[1], r = std::hypot(dn, de), above = s[2] - p[2];
        const double un = r > 0 ? dn / r : 0, ue = r > 0 ? de / r : 0;
        const double half = sim.near_radius(j) / (kOffsetBumps - 1);
        for (int a = 0; a < kOffsetBumps; ++a)
            for (int b = 0; b < kHeightBumps; ++b) {
                const double phi = bump(r, a * half, half) * bump(above, c.f.h.lo + b * c.f.h.step, c.f.h.width);
                const int k = g + a * kHeightBumps + b;
                row(k) += phi;
                row(k + kBumps) += phi * un;
                row(k + 2 * kBumps) += phi * ue;
            }
    }
}

void own_motion_inputs(const Context& c, std::size_t i, Eigen::RowVectorXd& row) {
    if (!c.sim.flying()) return;
    const double t = c.sim.stamps()[i];
    const auto v = c.sim.sufferer_velocity(t), ahead = c.sim.sufferer_velocity(t + kDifference_s),
               behind = c.sim.sufferer_velocity(t - kDifference_s);
    const int o = c.layout.at(InputGroup::own_motion);
    for (int k = 0; k < 3; ++k) {
        row(o + k) = v[static_cast<std::size_t>(k)];
        row(o + 3 + k) =
            (ahead[static_cast<std::size_t>(k)] - behind[static_cast<std::size_t>(k)]) / (2 * kDifference_s);
    }
}

// The prediction's own inputs: per axis p, p × powers of the push and of time (after the additive
// drift's bumps), dp/dt, p × direction, p × the shared push.
void prediction_inputs(const Context& c, std::size_t i, Eigen::RowVectorXd& row) {
    const auto& sim = c.sim;
    const double t = sim.stamps()[i], x = push_of(sim, c.f.sigma, c.pred, i) / c.f.top;
    const auto& drift = c.f.drift;
    const double half = 0.5 * (drift.t1 - drift.t0), tau = half > 0 ? (t - drift.t0) / half - 1 : 0;
    const std::size_t prev = i > 0 ? i - 1 : i, next = i + 1 < c.pred.size() ? i + 1 : i;
    const double dt = sim.stamps()[next] - sim.stamps()[prev];
    const int gs = c.layout.at(InputGroup::gain), ps = c.layout.at(InputGroup::push),
              ds = c.layout.at(InputGroup::drift) + drift.count, rs = c.layout.at(InputGroup::rate),
              vs = c.layout.at(InputGroup::direction), ss = c.layout.at(InputGroup::sharing);
    for (int a = 0; a < 6; ++a) {
        const auto A = static_cast<std::size_t>(a);
        if (!sim.measured_axes()[A]) continue;
        const double p = c.pred[i][A];
        row(gs + a) = p;
        for (int k = 0; k < kPushPowers; ++k) row(ps + a * kPushPowers + k) = p * std::pow(x, k + 1);
        for (int k = 0; k < kGainDriftPowers; ++k) row(ds + a * kGainDriftPowers + k) = p * std::pow(tau, k + 1);
        row(rs + a) = dt > 0 ? (c.pred[next][A] - c.pred[prev][A]) / dt : 0;
        row(vs + a) = p * c.info[i].direction;
        row(ss + a) = p * c.info[i].shared;
    }
}

// Sample i's regressors, in the layout's order.
Eigen::RowVectorXd inputs_of(const Context& c, std::size_t i) {
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(c.layout.columns);
    const double t = c.sim.stamps()[i];
    row(c.layout.at(InputGroup::constant)) = 1;
    const int dr = c.layout.at(InputGroup::drift);
    const auto& drift = c.f.drift;
    for (int k = 0; k < drift.count; ++k) row(dr + k) = bump(t, drift.t0 + k * kDriftSpacing_s, kDriftSpacing_s);
    geometry_inputs(c, i, row);
    own_motion_inputs(c, i, row);
    prediction_inputs(c, i, row);
    return row;
}

// One fold's held-out samples: their regressors and residuals, and the normal equations' parts XᵀX, XᵀY.
struct Gram {
    Eigen::MatrixXd x, y;  // one row per sample of `samples`
    std::vector<std::size_t> samples;
    Eigen::MatrixXd xx, xy;
};

// The folds' parts summed, but those of the folds `without`, on the columns `cols`.
Gram sum_without(const std::vector<Gram>& parts, const std::vector<int>& cols, std::size_t a,
                 std::size_t b = SIZE_MAX) {
    const auto k = static_cast<Eigen::Index>(cols.size());
    Gram g;
    g.xx = Eigen::MatrixXd::Zero(k, k);
    g.xy = Eigen::MatrixXd::Zero(k, parts[0].xy.cols());
    for (std::size_t f = 0; f < parts.size(); ++f)
        if (f != a && f != b) g.xx += parts[f].xx(cols, cols), g.xy += parts[f].xy(cols, Eigen::all);
    return g;
}

// Ridge coefficients (one column per axis) at penalty lambda × the mean diagonal; the constant (the
// first column) is not penalised.
Eigen::MatrixXd ridge(const Gram& g, double lambda) {
    Eigen::MatrixXd A = g.xx;
    const double l = lambda * A.trace() / static_cast<double>(A.cols());
    for (Eigen::Index k = 1; k < A.cols(); ++k) A(k, k) += l;
    return A.ldlt().solve(g.xy);
}

// For each axis, the penalty of kRidgeGrid whose fits on all but one of the folds other than
// `outer` predict the one left out best (nested blocked cross-validation: `outer` is never seen).
std::vector<double> choose_penalty(const std::vector<Gram>& parts, const std::vector<int>& cols, std::size_t outer) {
    const auto axes = static_cast<std::size_t>(parts[0].xy.cols());
    std::vector<double> best(axes, kRidgeGrid.front()), best_sse(axes, INFINITY);
    for (double lambda : kRidgeGrid) {
        std::vector<double> sse(axes, 0.0);
        for (std::size_t m = 0; m < parts.size(); ++m) {
            if (m == outer) continue;
            const Eigen::MatrixXd c = ridge(sum_without(parts, cols, outer, m), lambda);
            const Eigen::MatrixXd xx = parts[m].xx(cols, cols), xy = parts[m].xy(cols, Eigen::all);
            for (std::size_t a = 0; a < axes; ++a) {  // Σ(y − xc)² less Σy², which no penalty changes
                const auto col = c.col(static_cast<Eigen::Index>(a));
                sse[a] += col.dot(xx * col) - 2 * col.dot(xy.col(static_cast<Eigen::Index>(a)));
            }
        }
        for (std::size_t a = 0; a < axes; ++a)
            if (sse[a] < best_sse[a]) best_sse[a] = sse[a], best[a] = lambda;
    }
    return best;
}

// The candidates' rule (analysis/score.cpp) on the pieces, per axis; the best axis is the most
// significant among those whose held-out error falls by min_gain.
void judge(Discrepancy& r, const PieceErrors& s, const ExplainData& d, const ExplainOptions& o) {
    double total_n = 0, best_t = -INFINITY;
    bool best_gains = false;
    for (const auto& [piece, k] : s.n) total_n += static_cast<double>(k);
    for (std::size_t a = 0; a < 6; ++a) {
        if (!d.sim.measured_axes()[a]) continue;
        std::vector<double> diff;
        double before = 0, after = 0;
        for (const auto& [piece, b] : s.before) {
            diff.push_back((b[a] - s.after.at(piece)[a]) / static_cast<double>(s.n.at(piece)));
            before += b[a], after += s.after.at(piece)[a];
        }
        r.heldout_before[a] = std::sqrt(before / total_n) * d.sigma[a];
        r.heldout_after[a] = std::sqrt(after / total_n) * d.sigma[a];
        const double t = paired_z(diff), gain = before > 0 ? (before - after) / before : 0;
        r.axis_t[a] = t, r.axis_gain[a] = gain;
        const bool gains = gain >= o.min_gain;
        if ((gains && !best_gains) || (gains == best_gains && t > best_t))
            best_t = t, best_gains = gains, r.best_axis = static_cast<int>(a), r.gain = gain;
    }
    r.t = best_t;
    r.significant = r.t >= o.min_t && r.gain >= o.min_gain;
    r.note = log::cat(
        "a discrepancy learnt from the geometry, the model's own prediction, time and the sufferer's "
        "motion (",
        r.inputs, " inputs per axis) removes ", std::round(r.gain * 1000) / 10, " % of the held-out ",
        kAxes[static_cast<std::size_t>(r.best_axis)], " error (z = ", std::round(r.t * 10) / 10, ")",
        r.significant ? ": part of what is left is repeatable" : ": what is left is not repeatable");
}

// Per fold, its held-out samples' regressors (standardised over every sample, so that one penalty
// suits every input: column k times scale(k)) and residuals, with their normal equations' parts.
struct Design {
    std::vector<Gram> parts;
    Eigen::VectorXd scale;
    Frame frame;
    Layout layout;
};

Design design(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds,
              const physics::PredictionNoise& n, const std::vector<Wrench6>& weigh_by) {
    const Frame frame = frame_of(d, pred);
    const PushNoise push(d, weigh_by, n);
    const Context c{d.sim, d.info, pred, frame, layout_of(frame.drift.count)};
    std::vector<Gram> parts;
    Eigen::VectorXd sum_sq = Eigen::VectorXd::Zero(c.layout.columns);
    for (const auto& test : folds.test) {
        Gram g{Eigen::MatrixXd(static_cast<Eigen::Index>(test.size()), c.layout.columns),
               Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(test.size()), 6),
               test,
               {},
               {}};
        for (std::size_t r = 0; r < test.size(); ++r) {
            const auto row = static_cast<Eigen::Index>(r);
            // Each sample weighed by its noise: the floor and the turbulence that grows with the push
            // (analysis/noise.hpp's excess), so that the near passes' scatter does not drown the rest.
            double beyond = 0;
            for (std::size_t a = 0; a < 6; ++a)
                if (d.sim.measured_axes()[a]) beyond += push.relative(test[r], a);
            const double w = 1 / std::sqrt(1 + beyond);
            g.x.row(row) = w * inputs_of(c, test[r]);
            for (std::size_t a = 0; a < 6; ++a)
                if (d.sim.measured_axes()[a])
                    g.y(row, static_cast<Eigen::Index>(a)) = w * (d.sim.measured()[test[r]][a] - pred[test[r]][a]);
        }
        sum_sq += g.x.colwise().squaredNorm().transpose();
        parts.push_back(std::move(g));
    }
    Eigen::VectorXd scale = Eigen::VectorXd::Ones(sum_sq.size());
    for (Eigen::Index k = 1; k < scale.size(); ++k)
        if (sum_sq(k) > 0) scale(k) = std::sqrt(static_cast<double>(d.on_legs.size()) / sum_sq(k));
    for (auto& g : parts) {
        g.x = g.x * scale.asDiagonal();
        g.xx = g.x.transpose() * g.x;
        g.xy = g.x.transpose() * g.y;
    }
    return {std::move(parts), scale, frame, c.layout};
}

// The discrepancy on every input fitted on every fold (each axis at the penalty its
// cross-validation over the folds chooses), in the inputs' own units, with its frame.
physics::LearntDiscrepancy model_of(const Design& ds, const Discrepancy& r) {
    std::vector<int> cols(static_cast<std::size_t>(ds.layout.columns));
    std::iota(cols.begin(), cols.end(), 0);
    const auto lambda = choose_penalty(ds.parts, cols, SIZE_MAX);
    const Gram all = sum_without(ds.parts, cols, SIZE_MAX);
    physics::LearntDiscrepancy m;
    m.rows = 6, m.inputs = cols.size();
    m.coefficients.assign(m.rows * m.inputs, 0.0);
    for (std::size_t a = 0; a < 6; ++a) {
        const Eigen::VectorXd coef = ridge(all, lambda[a]).col(static_cast<Eigen::Index>(a));
        for (std::size_t k = 0; k < m.inputs; ++k)
            m.coefficients[a * m.inputs + k] =
                coef(static_cast<Eigen::Index>(k)) * ds.scale(static_cast<Eigen::Index>(k));
    }
    const Frame& f = ds.frame;
    m.height_lo_m = f.h.lo, m.height_step_m = f.h.step, m.height_width_m = f.h.width;
    m.t0_s = f.drift.t0, m.t1_s = f.drift.t1, m.drift_bumps = f.drift.count;
    m.push_top = f.top, m.sigma = f.sigma, m.heldout_gain = r.gain;
    return m;
}

// The discrepancy on the columns `cols`, cross-validated over the folds: its per-piece errors.
PieceErrors cross_validate(const ExplainData& d, const Folds& folds, const std::vector<Gram>& parts,
                           const std::vector<int>& cols) {
    PieceErrors s;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const auto lambda = choose_penalty(parts, cols, k);
        const Gram train = sum_without(parts, cols, k);
        Eigen::MatrixXd coef(train.xy.rows(), train.xy.cols());
        for (Eigen::Index a = 0; a < coef.cols(); ++a)
            coef.col(a) = ridge(train, lambda[static_cast<std::size_t>(a)]).col(a);
        const Eigen::MatrixXd left = parts[k].y - parts[k].x(Eigen::all, cols) * coef;  // less the discrepancy
        for (std::size_t i = 0; i < parts[k].samples.size(); ++i) {
            const int piece = piece_of(d, folds, parts[k].samples[i]);
            ++s.n[piece];
            for (std::size_t a = 0; a < 6; ++a) {
                const auto row = static_cast<Eigen::Index>(i), col = static_cast<Eigen::Index>(a);
                s.before[piece][a] += std::pow(parts[k].y(row, col) / d.sigma[a], 2);
                s.after[piece][a] += std::pow(left(row, col) / d.sigma[a], 2);
            }
        }
    }
    return s;
}

// Whether columns [start, start + count) hold any input (a flight over a stand has no own motion,
// a flight with one neighbour no shared push).
bool any_input(const std::vector<Gram>& parts, int start, int count) {
    for (const auto& g : parts)
        if (g.x.middleCols(start, count).squaredNorm() > 0) return true;
    return false;
}

// What the discrepancy depends on: each group's own share of the held-out gain on the best axis —
// the gain lost when that group's columns are left out — largest first; and each group's nested
// z, for the detection by structure.
void explain_dependence(Discrepancy& r, const ExplainData& d, const Folds& folds, const Design& ds,
                        const PieceErrors& full, const ExplainOptions& o) {
    const Layout& l = ds.layout;
    const std::vector<Gram>& parts = ds.parts;
    const auto a = static_cast<std::size_t>(r.best_axis);
    const double before = total(full.before, a), gained = before - total(full.after, a);
    if (!(gained > 0)) return;
    const double threshold = normal_upper(kStructureAlpha / static_cast<double>(kInputGroups.size() - 1));
    for (std::size_t g = 1; g < kInputGroups.size(); ++g) {
        if (l.count[g] == 0 || !any_input(parts, l.start[g], l.count[g])) continue;
        std::vector<int> cols;
        for (int k = 0; k < l.columns; ++k)
            if (k < l.start[g] || k >= l.start[g] + l.count[g]) cols.push_back(k);
        const PieceErrors without = cross_validate(d, folds, parts, cols);
        const double lost = total(without.after, a) - total(full.after, a);
        r.shares.emplace_back(kInputGroups[g].name, std::max(0.0, lost / gained));
        std::vector<double> diff;
        for (const auto& [piece, after] : full.after)
            diff.push_back((without.after.at(piece)[a] - after[a]) / static_cast<double>(full.n.at(piece)));
        const double z = paired_z(diff);
        r.group_z.emplace_back(kInputGroups[g].name, z);
        if (z >= threshold && lost / before >= o.min_gain && !r.structured)
            r.structured = true, r.structured_by = kInputGroups[g].name;
    }
    std::sort(r.shares.begin(), r.shares.end(), [](const auto& x, const auto& y) { return x.second > y.second; });
    if (r.shares.empty()) return;
    r.depends_on = r.shares.front().first;
    for (const auto& g : kInputGroups)
        if (r.depends_on == g.name) r.sentence = g.sentence;
}

}  // namespace

double total(const std::map<int, AxisValues>& pieces, std::size_t a) {
    double s = 0;
    for (const auto& [piece, v] : pieces) s += v[a];
    return s;
}

Discrepancy learn_discrepancy(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds,
                              const ExplainOptions& o, const DiscrepancyRun& run) {
    Discrepancy r;
    const Design ds =
        design(d, pred, folds, physics::prediction_noise_of(o.physics), run.weigh_by ? *run.weigh_by : pred);
    const Layout& l = ds.layout;
    std::vector<int> cols;
    for (std::size_t g = 0; g < kInputGroups.size(); ++g)
        if (std::find(run.without.begin(), run.without.end(), kInputGroups[g].group) == run.without.end())
            for (int k = 0; k < l.count[g]; ++k) cols.push_back(l.start[g] + k);
    r.inputs = cols.size();
    const PieceErrors s = cross_validate(d, folds, ds.parts, cols);
    r.fitted = true;
    judge(r, s, d, o);
    if (run.explain_dependence && r.significant) explain_dependence(r, d, folds, ds, s, o);
    if (run.pieces) *run.pieces = s;
    if (run.model) *run.model = model_of(ds, r);
    return r;
}

std::vector<Wrench6> discrepancy_at(const physics::LearntDiscrepancy& m, const Resimulation& sim,
                                    const std::vector<SampleInfo>& info, const std::vector<Wrench6>& pred) {
    const Context c{sim, info, pred, frame_of(m), layout_of(m.drift_bumps)};
    if (m.rows != 6 || m.inputs != static_cast<std::size_t>(c.layout.columns))
        throw InputError(log::cat("discrepancy: coefficients: ", m.rows, " rows of ", m.inputs,
                                  " inputs, where this build's discrepancy has 6 rows of ", c.layout.columns, " (for ",
                                  m.drift_bumps,
                                  " drift bumps): learnt by another version — explain the flight again"));
    const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> coef(
        m.coefficients.data(), 6, static_cast<Eigen::Index>(m.inputs));
    std::vector<Wrench6> out(pred.size(), Wrench6{});
    for (std::size_t i = 0; i < pred.size(); ++i) {
        const Eigen::VectorXd w = coef * inputs_of(c, i).transpose();
        for (std::size_t a = 0; a < 6; ++a)
            if (sim.measured_axes()[a]) out[i][a] = w(static_cast<Eigen::Index>(a));
    }
    return out;
}

}  // namespace dw::analysis
