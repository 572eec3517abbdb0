#include "analysis/score.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/stats.hpp"

namespace dw::analysis {

using flight::kAxes;

namespace {

// Whether the effect at its neutral (starting) values predicts what the model without it does — its
// start is then its absence (a clock offset of 0, a scale of 1), and an interval that holds it
// cannot tell the effect from no effect. (A flow effect may start at a typical value instead: a wake
// transport at the jet law's delay.)
constexpr double kAbsenceTolerance = 1e-9;  // noise floors
bool start_is_absence(Fit& fit, const Baseline& b, const Effect& e) {
    const auto& p = fit.predict(e.neutral());
    const auto& d = fit.data();
    for (auto i : d.on_legs)
        for (std::size_t a = 0; a < 6; ++a)
            if (d.sim.measured_axes()[a] && std::abs(p[i][a] - b.pred[i][a]) > kAbsenceTolerance * d.sigma[a])
                return false;
    return true;
}

}  // namespace

bool pinned(const Effect& e, const std::vector<double>& values) {
    for (std::size_t k = 0; k < values.size(); ++k) {
        const auto& p = e.params[k];
        const double tol = kPinnedFraction * (p.fit_max - p.fit_min);
        const bool at_lower = values[k] - p.fit_min < tol && std::abs(p.start - p.fit_min) > tol;
        if (at_lower || p.fit_max - values[k] < tol) return true;
    }
    return false;
}

namespace {

// A candidate that passes the whole-flight test and removes enough held-out error, but whose
// held-out evidence sits in so few pieces (about one per pass of a neighbour) that the sum over
// pieces cannot reach min_t whatever the data: the flight cannot decide it either way — not
// identifiable from this flight. (The signed ranks, the other half of the z, count the pieces that
// carry next to no evidence as much as the rest.) A label only: nothing is accepted by it.
bool too_few_pieces(const CandidateResult& c, const ExplainOptions& o) {
    return !c.accepted && c.gain >= o.min_gain && c.total_ratio < 1 && c.delta_bic < o.max_delta_bic &&
           std::sqrt(c.evidence_pieces) < o.min_t;
}

// Paired comparison over held-out legs.
void judge(CandidateResult& c, const PieceScores& s, const AxisValues& sigma, const ExplainOptions& o, double dbic) {
    const HeldOut h = judge_pieces(s, o.min_gain);
    c.axis_t = h.axis_t, c.axis_gain = h.axis_gain;
    c.best_axis = h.best_axis, c.gain = h.gain, c.evidence_pieces = h.evidence_pieces;
    const double best_t = h.t;
    double total_n = 0;
    for (const auto& [leg, k] : s.n) total_n += static_cast<double>(k);
    for (std::size_t a = 0; a < 6; ++a) {
        double b = 0, f = 0;
        for (const auto& [leg, x] : s.before) b += x[a];
        for (const auto& [leg, x] : s.after) f += x[a];
        c.heldout_before[a] = std::sqrt(b / total_n) * sigma[a];
        c.heldout_after[a] = std::sqrt(f / total_n) * sigma[a];
    }
    double tb = 0, ta = 0;
    for (std::size_t a = 0; a < 6; ++a)
        tb += c.heldout_before[a] * c.heldout_before[a] / (sigma[a] * sigma[a]),
            ta += c.heldout_after[a] * c.heldout_after[a] / (sigma[a] * sigma[a]);
    c.t = best_t;
    c.total_ratio = tb > 0 ? ta / tb : 1;
    c.delta_bic = dbic;
    c.accepted = c.t >= o.min_t && c.gain >= o.min_gain && ta < tb && dbic < o.max_delta_bic;
    c.too_few_pieces = too_few_pieces(c, o);
    c.note =
        log::cat("held-out ", kAxes[c.best_axis], ": z = ", std::round(c.t * 10) / 10,
                 " (signed ranks or sum over pieces of the held-out blocks), ", std::round(c.gain * 1000) / 10,
                 " % of its error removed; ΔBIC ", std::round(dbic), c.accepted ? " — accepted" : " — not accepted");
    if (c.too_few_pieces)
        c.note += log::cat(": its held-out evidence sits in ", std::round(c.evidence_pieces * 10) / 10,
                           " effective pieces, so the sum over pieces cannot exceed z ",
                           std::round(std::sqrt(c.evidence_pieces) * 10) / 10,
                           ": not identifiable from this flight (more passes would decide it)");
}

// How much of axis `to`'s residual the measured axis `from` explains by regression: the slope,
// and the squared error it removes.
std::pair<double, double> regress_residual(const ExplainData& d, const Baseline& b, int from, int to) {
    double xy = 0, xx = 0;
    for (auto i : d.on_legs) {
        const double x = d.sim.measured()[i][static_cast<std::size_t>(from)];
        xy += x * (d.sim.measured()[i][static_cast<std::size_t>(to)] - b.pred[i][static_cast<std::size_t>(to)]);
        xx += x * x;
    }
    return xx > 0 ? std::pair{xy / xx, xy * xy / xx} : std::pair{0.0, 0.0};
}

// An effect between two axes: the axis pair whose residual the model's other axis explains best.
Effect with_crosstalk_axes(Effect e, const ExplainData& d, const Baseline& b) {
    return with_crosstalk_axes(std::move(e), {{&d, &b}});
}

// The base model's own errors can look like a leak: the same regression on the axes of the same
// kind where no leak is claimed measures how much (the largest slope).
double crosstalk_discrepancy(const ExplainData& d, const Baseline& b, const Effect& e) {
    double disc = 0;
    const bool force = e.to < 3;
    for (int other = force ? 0 : 3; other < (force ? 3 : 6); ++other) {
        if (other == e.to || other == e.from) continue;
        disc = std::max(disc, std::abs(regress_residual(d, b, e.from, other).first));
    }
    return disc;
}

// Each fold fitted on its training legs (warm-started at `start`) and scored per piece of its
// held-out legs; the fold's values are appended to `fold_values` (for the jackknife).
PieceScores cross_validate(const ExplainData& d, const Baseline& b, const Effect& e, const std::vector<double>& start,
                           const Folds& folds, std::vector<std::vector<double>>& fold_values, std::stop_token stop) {
    PieceScores s;
    for (std::size_t k = 0; k < folds.train.size(); ++k) {
        throw_if_stopped(stop, "the fits");
        Fit fk(d, b.physics, e);
        auto [vk, sek] = fk.solve(start, folds.train[k], false, b.factor);
        fold_values.push_back(vk);
        const auto& p = fk.predict(vk);
        for (auto i : folds.test[k]) s.add(piece_of(d, folds, i), d, b.pred, p, i);
    }
    return s;
}

// 95 % intervals: the wider of the leg-fold jackknife (t, folds - 1 dof) and the covariance, with
// the tare's shared error added in quadrature (and crosstalk's discrepancy, see above).
void set_intervals(CandidateResult& c, const ExplainData& d, const Baseline& b, Fit& fit, const std::vector<double>& se,
                   const std::vector<std::vector<double>>& fold_values) {
    const auto tare = tare_spread(d, fit, c.effect, c.values, d.sim.tare_samples(b.physics));
    const auto jack = jackknife_sd(fold_values);
    const double t = t975(static_cast<int>(fold_values.size()) - 1);
    for (std::size_t p = 0; p < c.values.size(); ++p) {
        const double half = std::hypot(std::max(t * jack[p], kZ95 * se[p]), kZ95 * tare[p]);
        c.lo.push_back(c.values[p] - half);
        c.hi.push_back(c.values[p] + half);
    }
    if (c.effect.type->has_axes()) {
        const double disc = crosstalk_discrepancy(d, b, c.effect);
        c.lo[0] -= kZ95 * disc;
        c.hi[0] += kZ95 * disc;
    }
}

}  // namespace

Effect with_crosstalk_axes(Effect e, const std::vector<std::pair<const ExplainData*, const Baseline*>>& flights) {
    if (e.axes_given) return e;
    double best = -1;
    for (int from = 0; from < 6; ++from)
        for (int to = 0; to < 6; ++to) {
            double explained = 0;
            bool measured = from != to;
            for (const auto& [d, b] : flights) {
                const auto& m = d->sim.measured_axes();
                measured = measured && m[static_cast<std::size_t>(from)] && m[static_cast<std::size_t>(to)];
                const double sigma = d->sigma[static_cast<std::size_t>(to)];
                if (measured) explained += regress_residual(*d, *b, from, to).second / (sigma * sigma);
            }
            if (measured && explained > best) best = explained, e.from = from, e.to = to;
        }
    return e;
}

void PieceScores::add(long piece, const ExplainData& d, const std::vector<Wrench6>& before_pred,
                      const std::vector<Wrench6>& after_pred, std::size_t i) {
    ++n[piece];
    for (std::size_t a = 0; a < 6; ++a) {
        before[piece][a] += norm_sq(d, before_pred, i, a);
        after[piece][a] += norm_sq(d, after_pred, i, a);
        if (d.sim.measured_axes()[a]) change[piece] += std::pow((after_pred[i][a] - before_pred[i][a]) / d.sigma[a], 2);
    }
}

HeldOut judge_pieces(const PieceScores& s, double min_gain) {
    // The axis judged: the most significant among those whose held-out error falls by at least
    // min_gain (else the most significant of all, for the note).
    HeldOut h;
    h.t = -INFINITY;
    bool best_gains = false;
    for (std::size_t a = 0; a < 6; ++a) {
        std::vector<double> d;
        double before = 0, after = 0;
        for (const auto& [piece, b] : s.before) {
            const double nl = static_cast<double>(s.n.at(piece));
            if (s.change.at(piece) / nl < kEvidenceChange * kEvidenceChange) continue;
            d.push_back((b[a] - s.after.at(piece)[a]) / nl);
            before += b[a];
            after += s.after.at(piece)[a];
        }
        const double t = paired_z(d);
        const double gain = before > 0 ? (before - after) / before : 0;
        const bool gains = gain >= min_gain;
        h.axis_t[a] = t, h.axis_gain[a] = gain;
        if ((gains && !best_gains) || (gains == best_gains && t > h.t)) {
            h.t = t;
            best_gains = gains;
            h.best_axis = static_cast<int>(a);
            h.gain = gain;
            h.evidence_pieces = effective_count(d);
        }
    }
    return h;
}

int piece_of(const ExplainData& d, const Folds& folds, std::size_t i) {
    const int leg = d.info[i].leg;
    return leg * 1000 + static_cast<int>(std::floor((d.sim.stamps()[i] - folds.leg_start.at(leg)) / kPiece_s));
}

Folds folds_of(const ExplainData& d, int folds) {
    Folds f{std::vector<std::vector<std::size_t>>(static_cast<std::size_t>(folds)),
            std::vector<std::vector<std::size_t>>(static_cast<std::size_t>(folds)),
            {}};
    for (auto i : d.on_legs) {
        for (int k = 0; k < folds; ++k)
            (d.info[i].leg % folds == k ? f.test : f.train)[static_cast<std::size_t>(k)].push_back(i);
        if (!f.leg_start.count(d.info[i].leg)) f.leg_start[d.info[i].leg] = d.sim.stamps()[i];
    }
    return f;
}

namespace {

// One candidate on its axes as they are: screened on the whole flight by ΔBIC and identifiability,
// then cross-validated.
CandidateResult score_on_axes(const ExplainData& d, const Baseline& b, const Folds& folds, const Effect& e, int round,
                              const ExplainOptions& o) {
    CandidateResult c;
    c.round = round;
    c.effect = e;
    throw_if_stopped(o.stop, "the fits");
    Fit fit(d, b.physics, c.effect);
    auto [values, se] = fit.solve(c.effect.neutral(), d.on_legs, true, b.factor);
    c.values = values;
    const double dbic = b.n_eff * std::log(rss(d, fit.predict(values)) / rss(d, b.pred)) +
                        static_cast<double>(values.size()) * std::log(b.n_eff);
    c.delta_bic = dbic;
    if (dbic >= o.max_delta_bic) {
        c.note = log::cat("ΔBIC ", std::round(dbic), " on the whole flight: not worth a held-out test");
        c.lo = c.hi = values;
        return c;
    }
    if (pinned(c.effect, values)) {
        c.note = log::cat("ΔBIC ", std::round(dbic),
                          ", but a parameter is pinned at its bound: not identified (it stands in for something else)");
        c.lo = c.hi = values;
        return c;
    }
    std::vector<std::vector<double>> fold_values;
    const PieceScores s = cross_validate(d, b, c.effect, values, folds, fold_values, o.stop);
    set_intervals(c, d, b, fit, se, fold_values);
    judge(c, s, d.sigma, o, dbic);
    if (c.accepted && c.effect.holds_neutral(c.lo, c.hi) && start_is_absence(fit, b, c.effect)) {
        c.accepted = false;
        c.note = c.note.substr(0, c.note.rfind(" — accepted")) +
                 " — its 95 % interval holds its neutral value (the effect absent): not accepted";
    }
    for (const auto& [piece, err] : s.after) c.heldout_pieces[piece] = std::accumulate(err.begin(), err.end(), 0.0);
    return c;
}

}  // namespace

CandidateResult score(const ExplainData& d, const Baseline& b, const Folds& folds, Effect e, int round,
                      const ExplainOptions& o) {
    if (!e.type->has_axes() || e.axes_given) return score_on_axes(d, b, folds, e, round, o);
    return in_better_direction(
        with_crosstalk_axes(std::move(e), d, b),
        [&](const Effect& x) { return score_on_axes(d, b, folds, x, round, o); },
        [](const CandidateResult& c) { return c.t; });
}

}  // namespace dw::analysis
