#include "analysis/discrepancy.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/log.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

constexpr int kBumps = kOffsetBumps * kHeightBumps;
constexpr int kOwn = 7;                       // the constant and the sufferer's velocity and acceleration (n, e, d)
constexpr double kDifference_s = 0.02;        // the acceleration: velocities this far apart
constexpr int kGeometry = kOwn + 3 * kBumps;  // the bumps, then times the offset's n and e direction
constexpr double kHeightQuantiles[2] = {0.05, 0.95};

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
    double t0 = 0;
    int count = 0;
};

Drift drift_of(const ExplainData& d) {
    if (d.on_legs.empty()) return {};
    const double t0 = d.sim.stamps()[d.on_legs.front()], t1 = d.sim.stamps()[d.on_legs.back()];
    return {t0, static_cast<int>(std::floor((t1 - t0) / kDriftSpacing_s)) + 2};
}

// Sample i's regressors: the geometry's (kGeometry), then the drift's.
Eigen::RowVectorXd inputs_of(const ExplainData& d, std::size_t i, const Heights& h, const Drift& drift) {
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(kGeometry + drift.count);
    const double t = d.sim.stamps()[i];
    for (int k = 0; k < drift.count; ++k) row(kGeometry + k) = bump(t, drift.t0 + k * kDriftSpacing_s, kDriftSpacing_s);
    const auto s = d.sim.sufferer(t);
    row(0) = 1;
    if (d.sim.flying()) {
        const auto v = d.sim.sufferer_velocity(t), ahead = d.sim.sufferer_velocity(t + kDifference_s),
                   behind = d.sim.sufferer_velocity(t - kDifference_s);
        for (std::size_t k = 0; k < 3; ++k) {
            row(1 + static_cast<int>(k)) = v[k];
            row(4 + static_cast<int>(k)) = (ahead[k] - behind[k]) / (2 * kDifference_s);
        }
    }
    for (int j = 0; j < d.sim.neighbours(); ++j) {
        const auto p = d.sim.position(j, t);
        const double dn = p[0] - s[0], de = p[1] - s[1], r = std::hypot(dn, de), above = s[2] - p[2];
        const double un = r > 0 ? dn / r : 0, ue = r > 0 ? de / r : 0;
        const double half = d.sim.near_radius(j) / (kOffsetBumps - 1);
        for (int a = 0; a < kOffsetBumps; ++a)
            for (int b = 0; b < kHeightBumps; ++b) {
                const double phi = bump(r, a * half, half) * bump(above, h.lo + b * h.step, h.width);
                const int k = kOwn + a * kHeightBumps + b;
                row(k) += phi;
                row(k + kBumps) += phi * un;
                row(k + 2 * kBumps) += phi * ue;
            }
    }
    return row;
}

// One fold's held-out samples: their regressors and residuals, and the normal equations' parts XᵀX, XᵀY.
struct Gram {
    Eigen::MatrixXd x, y;  // one row per sample of `samples`
    std::vector<std::size_t> samples;
    Eigen::MatrixXd xx, xy;
};

// The folds' parts summed, but those of the folds `without`.
Gram sum_without(const std::vector<Gram>& parts, std::size_t a, std::size_t b = SIZE_MAX) {
    Gram g;
    g.xx = Eigen::MatrixXd::Zero(parts[0].xx.rows(), parts[0].xx.cols());
    g.xy = Eigen::MatrixXd::Zero(parts[0].xy.rows(), parts[0].xy.cols());
    for (std::size_t k = 0; k < parts.size(); ++k)
        if (k != a && k != b) g.xx += parts[k].xx, g.xy += parts[k].xy;
    return g;
}

// Ridge coefficients (one column per axis) at penalty lambda × the mean diagonal; the constant is not penalised.
Eigen::MatrixXd ridge(const Gram& g, double lambda) {
    Eigen::MatrixXd A = g.xx;
    const double l = lambda * A.trace() / static_cast<double>(A.cols());
    for (Eigen::Index k = 1; k < A.cols(); ++k) A(k, k) += l;
    return A.ldlt().solve(g.xy);
}

// For each axis, the penalty of kRidgeGrid whose fits on all but one of the folds other than
// `outer` predict the one left out best (nested blocked cross-validation: `outer` is never seen).
std::vector<double> choose_penalty(const std::vector<Gram>& parts, std::size_t outer) {
    const auto axes = static_cast<std::size_t>(parts[0].xy.cols());
    std::vector<double> best(axes, kRidgeGrid.front()), best_sse(axes, INFINITY);
    for (double lambda : kRidgeGrid) {
        std::vector<double> sse(axes, 0.0);
        for (std::size_t m = 0; m < parts.size(); ++m) {
            if (m == outer) continue;
            const Eigen::MatrixXd c = ridge(sum_without(parts, outer, m), lambda);
            for (std::size_t a = 0; a < axes; ++a) {  // Σ(y − xc)² less Σy², which no penalty changes
                const auto col = c.col(static_cast<Eigen::Index>(a));
                sse[a] += col.dot(parts[m].xx * col) - 2 * col.dot(parts[m].xy.col(static_cast<Eigen::Index>(a)));
            }
        }
        for (std::size_t a = 0; a < axes; ++a)
            if (sse[a] < best_sse[a]) best_sse[a] = sse[a], best[a] = lambda;
    }
    return best;
}

// Per held-out piece: squared residuals in noise floors, without and with the discrepancy.
struct PieceScores {
    std::map<int, AxisValues> before, after;
    std::map<int, std::size_t> n;
};

// The candidates' rule (analysis/score.cpp) on the pieces: the most significant axis among those
// whose held-out error falls by min_gain.
void judge(Discrepancy& r, const PieceScores& s, const ExplainData& d, const ExplainOptions& o) {
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
        const bool gains = gain >= o.min_gain;
        if ((gains && !best_gains) || (gains == best_gains && t > best_t))
            best_t = t, best_gains = gains, r.best_axis = static_cast<int>(a), r.gain = gain;
    }
    r.t = best_t;
    r.significant = r.t >= o.min_t && r.gain >= o.min_gain;
    r.note = log::cat("a discrepancy learnt from the geometry, the sufferer's motion and a slow drift (", r.inputs,
                      " inputs per axis) removes ", std::round(r.gain * 1000) / 10, " % of the held-out ",
                      kAxes[static_cast<std::size_t>(r.best_axis)], " error (z = ", std::round(r.t * 10) / 10, ")",
                      r.significant ? ": part of what is left is repeatable" : ": what is left is not repeatable");
}

// Per fold, its held-out samples' regressors (standardised over every sample, so that one penalty
// suits every input) and residuals, with their normal equations' parts.
std::vector<Gram> design(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds) {
    const Heights h = heights_of(d);
    const Drift drift = drift_of(d);
    std::vector<Gram> parts;
    Eigen::VectorXd sum_sq = Eigen::VectorXd::Zero(kGeometry + drift.count);
    for (const auto& test : folds.test) {
        Gram g{Eigen::MatrixXd(static_cast<Eigen::Index>(test.size()), kGeometry + drift.count),
               Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(test.size()), 6),
               test,
               {},
               {}};
        for (std::size_t r = 0; r < test.size(); ++r) {
            const auto row = static_cast<Eigen::Index>(r);
            g.x.row(row) = inputs_of(d, test[r], h, drift);
            for (std::size_t a = 0; a < 6; ++a)
                if (d.sim.measured_axes()[a])
                    g.y(row, static_cast<Eigen::Index>(a)) = d.sim.measured()[test[r]][a] - pred[test[r]][a];
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
    return parts;
}

}  // namespace

Discrepancy learn_discrepancy(const ExplainData& d, const std::vector<Wrench6>& pred, const Folds& folds,
                              const ExplainOptions& o) {
    Discrepancy r;
    const std::vector<Gram> parts = design(d, pred, folds);
    r.inputs = static_cast<std::size_t>(parts[0].x.cols());
    PieceScores s;
    for (std::size_t k = 0; k < parts.size(); ++k) {
        const auto lambda = choose_penalty(parts, k);
        const Gram train = sum_without(parts, k);
        Eigen::MatrixXd coef(train.xy.rows(), train.xy.cols());
        for (Eigen::Index a = 0; a < coef.cols(); ++a)
            coef.col(a) = ridge(train, lambda[static_cast<std::size_t>(a)]).col(a);
        const Eigen::MatrixXd left = parts[k].y - parts[k].x * coef;  // the residual less the discrepancy
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
    r.fitted = true;
    judge(r, s, d, o);
    return r;
}

}  // namespace dw::analysis
