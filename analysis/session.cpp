#include "analysis/session.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "analysis/fit.hpp"
#include "analysis/noise.hpp"
#include "analysis/select.hpp"
#include "core/errors.hpp"
#include "core/log.hpp"
#include "core/shutdown.hpp"
#include "core/stats.hpp"
#include "physics/bodies.hpp"

namespace dw::analysis {

namespace {

// A session's pieces are keyed by flight and piece: flight index × this + the flight's piece_of.
constexpr long kFlightKey = 100'000'000;
// The joint fit: golden-section search over the bracket the flights' own values span, widened by
// this fraction of the effect's search range on each side, to this fraction of the bracket.
constexpr double kBracketMargin = 0.05;
constexpr double kGoldenTolerance = 1e-6;

// One flight of the session, with what its fits read.
struct Member {
    const flight::Flight& f;
    std::string name;
    Resimulation sim;
    flight::Blocks blocks;
    std::vector<SampleInfo> info;
    std::optional<ExplainData> d;
    Baseline base, first;  // the current model; the model the session started from
    Folds folds;

    Member(const flight::Flight& fl, std::string n, const physics::PhysicsConfig& p, const ExplainOptions& o)
        : f(fl),
          name(std::move(n)),
          sim(fl, p),
          blocks(flight::find_blocks(fl, o.folds, physics::encounter_radii(fl.meta, p))),
          info(describe(sim, blocks, p)) {
        if (blocks.blocks.size() < static_cast<std::size_t>(o.folds))
            throw InputError(log::cat(name, ": poses.csv: ", blocks.blocks.size(), " cross-validation blocks (",
                                      flight::to_string(blocks.kind), "); cross-validation needs at least ", o.folds));
        auto pred = sim.recorded(p);
        const NoiseFloor floor = floor_of(sim, info, pred, p.stand.tare_s);
        d.emplace(explain_data(sim, info, blocks, o.folds, o.huber_delta, p, floor.sigma));
        base = first = baseline_of(*d, p, std::move(pred));
        folds = folds_of(*d, o.folds);
    }
};
using Members = std::vector<std::unique_ptr<Member>>;

// One effect's fits over the session's flights (each on its current model).
class JointFit {
public:
    JointFit(const Members& m, const Effect& e) : e_(e) {
        for (const auto& x : m) fits_.push_back(std::make_unique<Fit>(*x->d, x->base.physics, e));
    }
    Fit& at(std::size_t i) { return *fits_[i]; }
    // The value minimising the summed robust cost over rows[i] of each flight i (an empty row set
    // leaves that flight out), searched around the values in `around`.
    double solve(const std::vector<const std::vector<std::size_t>*>& rows, const std::vector<double>& around) {
        const auto& p = e_.params.front();
        const double margin = kBracketMargin * (p.fit_max - p.fit_min);
        double a = std::max(p.fit_min, *std::min_element(around.begin(), around.end()) - margin);
        double b = std::min(p.fit_max, *std::max_element(around.begin(), around.end()) + margin);
        const auto cost = [&](double v) {
            double c = 0;
            for (std::size_t i = 0; i < fits_.size(); ++i)
                if (!rows[i]->empty()) c += fits_[i]->robust_cost({v}, *rows[i]);
            return c;
        };
        const double g = (std::sqrt(5.0) - 1) / 2, tol = kGoldenTolerance * std::max(b - a, 1e-12);
        double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = cost(x1), f2 = cost(x2);
        while (b - a > tol) {
            if (f1 < f2) b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = cost(x1);
            else a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = cost(x2);
        }
        return 0.5 * (a + b);
    }

private:
    Effect e_;
    std::vector<std::unique_ptr<Fit>> fits_;
};

// The effect fitted on flight m alone: the single-flight explainer's score (its value, interval and
// verdict), or, where it stops at the whole-flight screen, the covariance's standard error; a value
// pinned at a bound is not seen (infinite error).
FlightFit fit_alone(Member& m, JointFit& jf, std::size_t i, const Effect& e, const ExplainOptions& o) {
    const CandidateResult c = score(*m.d, m.base, m.folds, e, 1, o);
    const bool same_axes = !e.type->has_axes() || (c.effect.from == e.from && c.effect.to == e.to);
    FlightFit r{c.values.front(), (c.hi.front() - c.lo.front()) / (2 * kZ95), c.accepted && same_axes};
    if (r.se <= 0 || !same_axes) {
        auto [v, se] = jf.at(i).solve(e.neutral(), m.d->on_legs, true, m.base.factor);
        r.value = v.front(), r.se = se.front();
    }
    if (pinned(e, {r.value})) r.se = INFINITY;
    return r;
}

// The flights whose fit gives a spread, with their fit's variance.
std::vector<std::pair<double, double>> seen_estimates(const RigCandidate& c) {
    std::vector<std::pair<double, double>> out;
    for (const auto& f : c.per_flight)
        if (f.seen()) out.emplace_back(f.value, f.se * f.se);
    return out;
}

// The flights' own values pooled as random effects (the known natural spread counted): the one-value
// test (Cochran's Q against its limit), the spread between flights, and the session's value and
// interval. Fewer than two flights seeing it: no test, and the value of the joint fit without an
// interval.
void pool_flights(RigCandidate& c, double joint) {
    const RandomEffects r = random_effects(seen_estimates(c), c.known_sd);
    c.value = joint, c.lo = -INFINITY, c.hi = INFINITY;
    if (r.dof < 1) return;
    c.q = r.q, c.dof = r.dof, c.q_limit = chi2_upper(kOneValueLevel, r.dof), c.one_value = c.q <= c.q_limit;
    c.between_sd = r.between_sd;
    c.value = r.mean, c.lo = r.mean - r.half95, c.hi = r.mean + r.half95;
}

// The axes of a cross-talk for the session: chosen on every flight's residual at once.
Effect with_session_axes(const Members& m, Effect e) {
    if (!e.type->has_axes()) return e;
    std::vector<std::pair<const ExplainData*, const Baseline*>> flights;
    for (const auto& x : m) flights.emplace_back(&*x->d, &x->base);
    return with_crosstalk_axes(std::move(e), flights);
}

// Held out over every flight's pieces: each fold fitted jointly on every flight's training blocks.
HeldOut pooled_heldout(Members& m, JointFit& jf, RigCandidate& c, const ExplainOptions& o, double around) {
    PieceScores s;
    for (std::size_t k = 0; k < static_cast<std::size_t>(o.folds); ++k) {
        throw_if_stopped(o.stop, "the session's fits");
        std::vector<const std::vector<std::size_t>*> rows;
        for (const auto& x : m) rows.push_back(&x->folds.train[k]);
        const double v = jf.solve(rows, {around, c.lo, c.hi});
        for (std::size_t i = 0; i < m.size(); ++i) {
            const auto& p = jf.at(i).predict({v});
            for (auto r : m[i]->folds.test[k])
                s.add(static_cast<long>(i) * kFlightKey + piece_of(*m[i]->d, m[i]->folds, r), *m[i]->d, m[i]->base.pred,
                      p, r);
        }
    }
    for (const auto& [piece, err] : s.after)
        c.pieces_after[piece] = err[0] + err[1] + err[2] + err[3] + err[4] + err[5];
    return judge_pieces(s, o.min_gain);
}

// The flights' own values where they see the effect (all of them where none does), but flight `left_out`.
std::vector<double> seen_values(const RigCandidate& c, std::size_t left_out = SIZE_MAX) {
    std::vector<double> seen, all;
    for (std::size_t i = 0; i < c.per_flight.size(); ++i) {
        if (i == left_out) continue;
        all.push_back(c.per_flight[i].value);
        if (std::isfinite(c.per_flight[i].se)) seen.push_back(c.per_flight[i].value);
    }
    return seen.empty() ? all : seen;
}

// Held out by whole flights: each flight predicted by the fit on the others.
HeldOut left_out_heldout(Members& m, JointFit& jf, const RigCandidate& c, const ExplainOptions& o) {
    PieceScores s;
    const std::vector<std::size_t> none;
    for (std::size_t j = 0; j < m.size(); ++j) {
        throw_if_stopped(o.stop, "the session's fits");
        std::vector<const std::vector<std::size_t>*> rows;
        for (std::size_t i = 0; i < m.size(); ++i) rows.push_back(i == j ? &none : &m[i]->d->on_legs);
        const double v = jf.solve(rows, seen_values(c, j));
        const auto& p = jf.at(j).predict({v});
        for (auto r : m[j]->d->on_legs)
            s.add(static_cast<long>(j) * kFlightKey + piece_of(*m[j]->d, m[j]->folds, r), *m[j]->d, m[j]->base.pred, p,
                  r);
    }
    return judge_pieces(s, o.min_gain);
}

bool holds_neutral(const RigCandidate& c) { return c.effect.holds_neutral({c.lo}, {c.hi}); }

bool passes_heldout(const RigCandidate& c, const ExplainOptions& o) {
    return c.pooled.t >= o.min_t && c.left_out.t >= o.min_t && c.pooled.gain >= o.min_gain;
}

std::string verdict_note(const RigCandidate& c, const ExplainOptions& o) {
    std::string z = log::cat("held out over every flight's pieces z = ", fixed(c.pooled.t, 1), " (",
                             fixed(c.pooled.gain * 100, 1), " % of ", flight::kAxes[c.pooled.best_axis],
                             "'s error removed), by whole flights z = ", fixed(c.left_out.t, 1));
    if (!c.one_value)
        z += log::cat("; not one value for the session: fitted per flight, the values differ beyond their spread (Q = ",
                      fixed(c.q, 1), " > ", fixed(c.q_limit, 1), ", ", c.dof, " degrees of freedom)");
    if (!passes_heldout(c, o)) return z + " — not accepted";
    if (!c.one_value) return z + " — refused";
    if (holds_neutral(c)) return z + "; but its interval holds its neutral value — not accepted";
    return z + " — accepted";
}

RigCandidate score_rig(Members& m, const Effect& effect, int round, const SessionOptions& so) {
    const ExplainOptions& o = so.explain;
    RigCandidate c;
    c.effect = with_session_axes(m, effect);
    c.round = round;
    if (const auto k = so.between_flight_sd.find(spread_key(c.effect)); k != so.between_flight_sd.end())
        c.known_sd = k->second;
    JointFit jf(m, c.effect);
    for (std::size_t i = 0; i < m.size(); ++i) c.per_flight.push_back(fit_alone(*m[i], jf, i, c.effect, o));
    std::vector<const std::vector<std::size_t>*> all;
    for (const auto& x : m) all.push_back(&x->d->on_legs);
    const double joint = jf.solve(all, seen_values(c));
    c.left_out = left_out_heldout(m, jf, c, o);
    pool_flights(c, joint);
    c.pooled = pooled_heldout(m, jf, c, o, c.value);
    c.accepted = passes_heldout(c, o) && c.one_value && !holds_neutral(c);
    c.not_one_value = passes_heldout(c, o) && !c.one_value;
    c.note = verdict_note(c, o);
    return c;
}

// A cross-talk on the session's pair, in_better_direction (score.hpp) by the pieces of all flights.
RigCandidate score_rig_directed(Members& m, const Effect& effect, int round, const SessionOptions& so) {
    if (!effect.type->has_axes() || effect.axes_given) return score_rig(m, effect, round, so);
    return in_better_direction(
        with_session_axes(m, effect), [&](const Effect& x) { return score_rig(m, x, round, so); },
        [](const RigCandidate& c) { return c.pooled.t; });
}

// The rig's candidates: the effects of the measurement chain that act on every flight of the session
// (one parameter each: a joint fit searches one value).
std::vector<Effect> rig_candidates(const Members& m, const ExplainOptions& o) {
    std::vector<Effect> out;
    for (const auto& e : o.candidates)
        if (physics::of_the_rig(*e.type) && e.params.size() == 1 && std::all_of(m.begin(), m.end(), [&](const auto& x) {
                return e.type->applies(x->sim.neighbours(), x->sim.flying());
            }))
            out.push_back(e);
    return out;
}

// The other members of b's family scored in its round, accepted or not, that the held-out pieces
// cannot tell from it (their paired z against b below min_t), as the single-flight explainer names them.
std::vector<std::string> alike_in_family(const std::vector<RigCandidate>& round, const RigCandidate& b,
                                         const ExplainOptions& o) {
    std::vector<std::string> out;
    const auto* family = b.effect.type->family();
    for (const auto& c : round) {
        if (!family || c.effect.name == b.effect.name || c.effect.type->family() != family) continue;
        std::vector<double> d;
        for (const auto& [piece, e] : b.pieces_after)
            if (c.pieces_after.count(piece)) d.push_back(c.pieces_after.at(piece) - e);
        if (paired_z(d) < o.min_t) out.push_back(c.effect.name);
    }
    return out;
}

// The best accepted candidate of a round (none: nullptr).
const RigCandidate* best_of(const std::vector<RigCandidate>& round) {
    const RigCandidate* best = nullptr;
    for (const auto& c : round)
        if (c.accepted && (!best || c.pooled.t > best->pooled.t)) best = &c;
    return best;
}

// Forward selection of the rig's effects, each round on top of the last round's.
void select_rig(Members& m, SessionResult& R, const SessionOptions& so, const Progress& say) {
    const ExplainOptions& o = so.explain;
    auto remaining = rig_candidates(m, o);
    for (int round = 1; round <= o.max_effects && !remaining.empty(); ++round) {
        std::vector<RigCandidate> scored;
        for (const auto& e : remaining) {
            say(log::cat("round ", round, ": ", e.name, " fitted over the session's ", m.size(), " flights"));
            scored.push_back(score_rig_directed(m, e, round, so));
            say("  " + scored.back().note);
        }
        R.candidates.insert(R.candidates.end(), scored.begin(), scored.end());
        for (const auto& c : scored)
            if (c.not_one_value && std::find(R.refused_not_one_value.begin(), R.refused_not_one_value.end(),
                                             c.effect.name) == R.refused_not_one_value.end())
                R.refused_not_one_value.push_back(c.effect.name);
        const RigCandidate* best = best_of(scored);
        if (!best) break;
        RigCandidate b = *best;
        b.family_alike = alike_in_family(scored, b, o);
        for (auto& x : m) {
            physics::PhysicsConfig p = x->base.physics;
            b.effect.apply(p, {b.value});
            x->base = baseline_of(*x->d, p);
        }
        std::erase_if(remaining, [&](const Effect& e) {
            return e.name == b.effect.name ||
                   std::find(b.family_alike.begin(), b.family_alike.end(), e.name) != b.family_alike.end();
        });
        R.accepted.push_back(std::move(b));
    }
}

std::string value_text(const RigCandidate& c) {
    const auto& p = c.effect.params.front();
    return log::cat(c.effect.name, " ", p.name, " ", fixed(c.value, 4), " [", fixed(c.lo, 4), ", ", fixed(c.hi, 4), "]",
                    p.unit.empty() ? "" : " " + p.unit);
}

std::string session_verdict(const SessionResult& R) {
    std::vector<std::string> parts;
    for (const auto& c : R.accepted) {
        std::string s = log::cat("the rig: ", value_text(c), ", one value over the ", R.flights.size(),
                                 " flights (one flight alone shows it on ", c.alone_count(), ")");
        if (!c.family_alike.empty())
            s += log::cat("; ", c.effect.type->family()->shared, ": ", c.effect.name, " or ", log::join(c.family_alike),
                          " — this session cannot tell which");
        parts.push_back(s);
    }
    if (R.accepted.empty())
        parts.push_back(log::cat("the rig: nothing beyond the physics over the ", R.flights.size(), " flights"));
    if (!R.refused_not_one_value.empty())
        parts.push_back(log::cat("not one value for the session (the flights differ in it beyond their spread): ",
                                 log::join(R.refused_not_one_value)));
    return log::join(parts, "; ");
}

// Each flight's own effects (those not of the rig), on top of the session's rig.
void explain_flights(Members& m, SessionResult& R, const ExplainOptions& o, const Progress& say) {
    ExplainOptions eo = o;
    std::erase_if(eo.candidates, [](const Effect& e) { return physics::of_the_rig(*e.type); });
    for (std::size_t i = 0; i < m.size(); ++i) {
        say(log::cat(m[i]->name, ": its own effects, on top of the session's rig"));
        eo.physics = m[i]->base.physics;
        R.rows[i].own = explain(m[i]->f, eo);
    }
}

}  // namespace

void require_session_size(std::size_t flights) {
    if (flights < kMinSessionFlights)
        throw InputError(
            log::cat("--flights: a session is ", kMinSessionFlights, " flights or more (given ", flights, ")"));
}

std::string spread_key(const Effect& e) {
    if (!e.type->has_axes()) return e.name;
    return log::cat(e.name, " ", flight::kAxes[static_cast<std::size_t>(e.from)], "->",
                    flight::kAxes[static_cast<std::size_t>(e.to)]);
}

SessionResult explain_session(const std::vector<flight::Flight>& flights, const std::vector<std::string>& names,
                              const SessionOptions& so) {
    const ExplainOptions& o = so.explain;
    validate(o);
    require_session_size(flights.size());
    if (names.size() != flights.size()) throw InputError("session: one name per flight");
    if (!so.per_flight_physics.empty() && so.per_flight_physics.size() != flights.size())
        throw InputError("session: one base physics per flight, or none");
    const auto started = std::chrono::steady_clock::now();
    const Progress say = [&](const std::string& s) {
        if (o.progress) o.progress(s);
    };
    SessionResult R;
    R.flights = names;
    Members m;
    for (std::size_t i = 0; i < flights.size(); ++i) {
        if (flights[i].meta.neighbours.empty())
            throw InputError(log::cat(names[i], ": meta.json: no neighbour, so no downwash for a session to explain"));
        const auto& p = so.per_flight_physics.empty() ? o.physics : so.per_flight_physics[i];
        m.push_back(std::make_unique<Member>(flights[i], names[i], p, o));
    }
    select_rig(m, R, so, say);
    for (const auto& x : m) {
        R.rows.push_back({x->name, x->d->on_legs.size(), x->d->sigma, residual_rms(*x->d, x->first.pred),
                          residual_rms(*x->d, x->base.pred), std::nullopt});
        R.fitted.push_back(x->base.physics);
    }
    if (so.flight_effects) explain_flights(m, R, o, say);
    R.verdict = session_verdict(R);
    R.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    return R;
}

std::size_t RigCandidate::flights_to_resolve(double half_width) const {
    if (!std::isfinite(resolution()) || dof < 1) return 0;
    // The interval is t(dof) × each flight's pooled spread / √(the dof + 1 flights that see it).
    const double per_flight_sd = resolution() / t975(dof) * std::sqrt(dof + 1.0);
    for (std::size_t n = 2; n <= kMaxPlannedFlights; ++n)
        if (t975(static_cast<int>(n) - 1) * per_flight_sd / std::sqrt(static_cast<double>(n)) <= half_width) return n;
    return 0;
}

std::size_t RigCandidate::alone_count() const {
    return static_cast<std::size_t>(
        std::count_if(per_flight.begin(), per_flight.end(), [](const FlightFit& f) { return f.alone_accepted; }));
}

}  // namespace dw::analysis
