#pragma once
// A lab's session explained as one: several flights flown with the same rig. The rig's effects —
// those of its measurement chain (physics::of_the_rig: the sensor's response, the calibration, the
// stamps' clock) — are one value for the session, so they are fitted jointly over every flight and
// their evidence pooled; the rest stays each flight's own (explain(), per flight, on top of the
// session's rig).
//
// A rig effect is accepted when, round by round as in the single-flight explainer:
// - held out, it predicts better over the pieces of all flights (each flight's blocked folds, the
//   fit made jointly on every flight's training blocks), and over whole flights left out in turn
//   (the fit made on the other flights): both z >= min_t, and the pooled gain >= min_gain;
// - it is one value: fitted on each flight alone, the values agree within their spread (Cochran's
//   Q below its 1 % chi-square quantile); else it is refused, and the report says so;
// - its interval does not hold its neutral value.
// Its value and interval are the flights' own fits pooled as random effects: each flight weighed by
// its error with the spread between flights added (Paule-Mandel: the spread that brings Cochran's Q
// to its degrees of freedom, beside any natural spread known), the interval Student's t with
// flights − 1 degrees of freedom (Hartung-Knapp). Flights that differ by nature widen it, so five
// flights whose gains scatter by 0.2 resolve a common gain only to about ±0.25.
#include <cmath>
#include <functional>
#include <optional>
#include <stop_token>
#include <string>
#include <vector>

#include "analysis/explain.hpp"
#include "analysis/score.hpp"

namespace dw::analysis {

// The one-value test's level: values of one rig effect fitted per flight that differ more than
// chance at this level would are not one value.
inline constexpr double kOneValueLevel = 0.01;
// A session is at least this many flights (one leaves out, one is left); fewer: dw::InputError.
inline constexpr std::size_t kMinSessionFlights = 2;
void require_session_size(std::size_t flights);

struct SessionOptions {
    ExplainOptions explain;  // the physics every flight is compared with, and the thresholds
    // Each flight's own base physics, when given (one per flight): the session proof explains on
    // top of each flight's own fit. Empty: explain.physics for every flight.
    std::vector<physics::PhysicsConfig> per_flight_physics;
    bool flight_effects = true;  // then each flight's own effects, on top of the session's rig
    // The spread an effect's per-flight values have by nature (name -> standard deviation): the
    // flights' own variation — a push that differs from trial to trial shows as a gain that does —
    // measured on an earlier session of the rig (its between_flight_sd), keyed by spread_key. The
    // one-value test and the interval count it beside each flight's own error; none named: none known.
    std::map<std::string, double> between_flight_sd;
};

// An effect's key in between_flight_sd: its name, and an effect between two axes its axes too
// ("<effect> f_d->f_n").
std::string spread_key(const Effect& e);

// One rig effect, fitted on one flight alone.
struct FlightFit {
    // se: the single-flight explainer's interval's (else the covariance's, inflated for
    // autocorrelation); infinite where the flight cannot see it (a value pinned at a bound).
    double value = 0, se = 0;
    bool alone_accepted = false;  // the single-flight explainer's test on that flight alone accepts it
    bool seen() const { return std::isfinite(se) && se > 0; }  // a spread to weigh it by
};

struct RigCandidate {
    Effect effect;
    int round = 1;
    double value = 0, lo = 0, hi = 0;  // the session's value (the flights' pooled) and its 95 % interval
    std::vector<FlightFit> per_flight;
    double q = 0, q_limit = 0;  // Cochran's Q of the per-flight values, and its 1 % limit
    int dof = 0;
    double known_sd = 0;    // the natural spread counted (SessionOptions::between_flight_sd)
    double between_sd = 0;  // the per-flight values' spread beyond their errors (Paule-Mandel, with known_sd)
    bool one_value = true;
    HeldOut pooled, left_out;             // over every flight's held-out pieces; over whole flights left out
    std::map<long, double> pieces_after;  // pooled: per piece, the normalised squared error after
    bool accepted = false;
    bool not_one_value = false;             // it passed the held-out tests, but the flights differ in it: refused
    std::vector<std::string> family_alike;  // accepted alongside: members of its family the session cannot tell from it
    std::string note;
    std::size_t alone_count() const;
    // What the session resolves: its interval's half-width; and how many flights like these would
    // resolve `half_width` (each flight's pooled spread — its error and the spread between flights —
    // over √n, times Student's t with n − 1 degrees of freedom), 0 where even kMaxPlannedFlights
    // would not or there is no interval.
    double resolution() const { return 0.5 * (hi - lo); }
    std::size_t flights_to_resolve(double half_width) const;
};
inline constexpr std::size_t kMaxPlannedFlights = 1000;

struct SessionFlightRow {
    std::string name;
    std::size_t samples = 0;
    AxisValues noise_floor{};
    AxisValues rms_before{}, rms_after{};  // the residual's RMS without and with the session's rig effects
    std::optional<ExplainResult> own;      // its own effects, on top of the session's rig
};

struct SessionResult {
    std::vector<std::string> flights;
    std::vector<RigCandidate> candidates;  // every score, every round
    std::vector<RigCandidate> accepted;
    std::vector<std::string> family_sentences;
    std::vector<std::string> refused_not_one_value;  // passed the held-out tests but differ per flight
    std::vector<SessionFlightRow> rows;
    std::vector<physics::PhysicsConfig> fitted;  // per flight: its base with the session's rig effects
    std::string verdict;
    double seconds = 0;
};

// Throws dw::InputError for fewer than kMinSessionFlights flights, a flight without a neighbour, or
// per_flight_physics of another length; dw::Stopped on a stop request.
SessionResult explain_session(const std::vector<flight::Flight>& flights, const std::vector<std::string>& names,
                              const SessionOptions& o);

// The natural between-flight spreads a session.json measured (each rig candidate of its first round:
// spread_key -> between_flight_sd), for SessionOptions::between_flight_sd. Throws dw::InputError
// naming the file and what is wrong with it.
std::map<std::string, double> spreads_from(const std::string& session_json);

// session.json, session.md and each flight's own report (when explained) into dir.
void write_session_report(const std::vector<flight::Flight>& flights, const SessionResult& r, const SessionOptions& o,
                          const std::string& dir);

}  // namespace dw::analysis
