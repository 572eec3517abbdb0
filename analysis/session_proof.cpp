#include "analysis/session_proof.hpp"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "analysis/session.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

struct Session {
    std::string name;
    std::vector<flight::Flight> flights;
    std::vector<std::string> names;
};

// The flights with a neighbour in groups of session_size: in order, or dealt in turn (flight k to
// session k mod the number of sessions); flights beyond the last full group are left out.
std::vector<Session> sessions_of(const SessionProofOptions& o) {
    std::vector<std::pair<flight::Flight, std::string>> flights;
    for (const auto& path : o.flights) {
        auto f = flight::read_flight(path);
        if (!f.meta.neighbours.empty()) flights.emplace_back(std::move(f), fs::path(path).filename().string());
    }
    const std::size_t n = flights.size() / o.session_size;
    if (n == 0)
        throw InputError(
            log::cat("--flights: fewer than ", o.session_size, " flights with a neighbour: no session of that size"));
    flights.resize(n * o.session_size);
    std::vector<Session> out(n);
    for (std::size_t k = 0; k < flights.size(); ++k) {
        auto& s = out[o.interleave ? k % n : k / o.session_size];
        s.flights.push_back(std::move(flights[k].first));
        s.names.push_back(flights[k].second);
    }
    if (o.max_sessions > 0 && out.size() > o.max_sessions) out.resize(o.max_sessions);
    for (auto& s : out) s.name = log::join(s.names, " ");
    return out;
}

std::string found_of(const SessionResult& r) {
    std::vector<std::string> v;
    for (const auto& a : r.accepted)
        v.push_back(a.family_alike.empty() ? a.effect.name
                                           : log::cat(a.effect.name, " (or ", log::join(a.family_alike), ")"));
    return v.empty() ? "(none)" : log::join(v);
}

// Whether c is the concealed effect as concealed (a cross-talk: between the concealed axes).
bool as_concealed(const RigCandidate& c, const std::string& effect) {
    return c.effect.name == effect && on_concealed_axes(*c.effect.type, {c.effect.from, c.effect.to});
}

// The untouched session's value of an effect on top of its own fit (its first round): from r when
// it scored it as concealed, else fitted on the session again with the concealed axes given.
double untouched_value(const Session& s, SessionOptions so, const SessionResult& r, const std::string& effect) {
    for (const auto& c : r.candidates)
        if (c.round == 1 && as_concealed(c, effect)) return c.value;
    auto e = effects_named({effect}).front();
    const auto axes = e.type->real_concealment()->axes;
    e.from = axes.from, e.to = axes.to, e.axes_given = true;
    so.explain.candidates = {e};
    so.explain.max_effects = 1;
    const auto on_axes = explain_session(s.flights, s.names, so);
    return on_axes.candidates.empty() ? e.neutral().front() : on_axes.candidates.front().value;
}

// The natural spread of each effect over the session's flights: the untouched session's, fitted per flight.
std::map<std::string, double> spread_of(const SessionResult& untouched) {
    std::map<std::string, double> out;
    for (const auto& c : untouched.candidates)
        if (c.round == 1) out[spread_key(c.effect)] = c.between_sd;
    return out;
}

// Whether the concealed effect t is recovered: accepted with t inside its interval, or an accepted
// member of its family names it alike; and nothing outside its family claimed.
void check(SessionProofRow& row, const SessionResult& r, const Truth& t) {
    row.found = found_of(r);
    const RigCandidate* hit = nullptr;
    for (const auto& a : r.accepted) {
        const bool alike = std::find(a.family_alike.begin(), a.family_alike.end(), t.effect) != a.family_alike.end();
        if (as_concealed(a, t.effect) || alike) {
            hit = &a;
            row.family_named = a.effect.name != t.effect;
        } else if (!a.effect.type->family() || a.effect.type->family() != physics::effect_type(t.effect).family()) {
            row.why += a.effect.name + " claimed too. ";
        } else {
            row.why += log::cat(a.effect.name, " named alone for ", t.effect, ". ");
        }
    }
    for (const auto& c : r.candidates)
        if (c.effect.name == t.effect && c.round == 1) {
            row.alone = c.alone_count();
            row.fitted = log::cat(fixed(c.value, 4), " [", fixed(c.lo, 4), ", ", fixed(c.hi, 4), "]");
        }
    row.flights = r.flights.size();
    if (!hit) row.why += t.effect + " not accepted. ";
    if (hit && !row.family_named && (t.value < hit->lo || t.value > hit->hi))
        row.why += t.param + " outside the interval. ";
    row.pass = row.why.empty();
}

std::string table(const std::vector<SessionProofRow>& rows) {
    std::ostringstream md;
    md << "| session | concealed in every flight | expected | found | session fit [95 %] | one flight alone "
          "accepts it | verdict |\n|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
        md << "| " << r.session << " | " << r.concealed << " | " << r.expected << " | " << r.found << " | " << r.fitted
           << " | " << (r.untouched ? "–" : log::cat(r.alone, " of ", r.flights)) << " | "
           << (r.pass ? (r.family_named ? "PASS (family named)" : "PASS") : "FAIL: " + r.why) << " |\n";
    return md.str();
}

// One session: untouched, on its own fit, then each concealment on top of its own fit.
void prove_session(const Session& s, const fs::path& dir, const SessionProofOptions& o,
                   const std::vector<Concealment>& cases, SessionProofResult& R) {
    const auto say = [&](const std::string& x) {
        if (o.progress) o.progress(x);
    };
    SessionOptions so;
    so.explain.physics = o.physics;
    so.explain.stop = o.stop;
    so.flight_effects = false;
    say(log::cat("session ", s.name, ": its flights' natural spread, untouched"));
    so.between_flight_sd = spread_of(explain_session(s.flights, s.names, so));
    say(log::cat("session ", s.name, ": explaining it untouched, its natural spread known"));
    const auto own = explain_session(s.flights, s.names, so);
    write_session_report(s.flights, own, so, (dir / "untouched").string());
    so.per_flight_physics = own.fitted;  // from here on, on top of the session's own fit
    const auto again = explain_session(s.flights, s.names, so);
    write_session_report(s.flights, again, so, (dir / "untouched_on_own_fit").string());
    SessionProofRow null_row{s.name,
                             "nothing (its own fit: " + found_of(own) + ")",
                             "nothing new",
                             found_of(again),
                             "–",
                             0,
                             s.flights.size(),
                             true,
                             again.accepted.empty(),
                             false,
                             again.accepted.empty() ? "" : "claimed on its own fit. "};
    R.rows.push_back(null_row);
    ++R.untouched;
    R.clean += null_row.pass ? 1 : 0;
    say(log::cat("  on its own fit: ", null_row.found));
    for (const auto& c : cases) {
        auto hidden = s.flights;
        for (auto& f : hidden) c.conceal(f);
        const auto r = explain_session(hidden, s.names, so);
        write_session_report(hidden, r, so, (dir / c.name).string());
        const Truth t = c.expect(own.fitted.front().effects, untouched_value(s, so, again, c.name));
        SessionProofRow row{s.name, c.description, log::cat(t.param, " ", fixed(t.value, 4)), "", "", 0, 0};
        check(row, r, t);
        ++R.concealed;
        R.recovered += row.pass ? 1 : 0;
        say(log::cat("  concealed ", c.name, ": found ", row.found, row.pass ? " — PASS" : " — FAIL: " + row.why));
        R.rows.push_back(row);
    }
}

}  // namespace

SessionProofResult run_session_proof(const SessionProofOptions& o) {
    auto cases = concealments(o.concealed);
    for (const auto& n : o.cases)
        if (std::none_of(cases.begin(), cases.end(), [&](const Concealment& c) { return c.name == n; }))
            throw InputError(log::cat("--cases: unknown case '", n, "' (expected ", concealment_names(), ")"));
    if (!o.cases.empty())
        std::erase_if(cases, [&](const Concealment& c) {
            return std::find(o.cases.begin(), o.cases.end(), c.name) == o.cases.end();
        });
    const auto sessions = sessions_of(o);  // every input read before any output is made
    StagedFolder staged(o.out_dir);
    SessionProofResult R;
    for (std::size_t k = 0; k < sessions.size(); ++k)
        prove_session(sessions[k], fs::path(staged.path()) / log::cat("session_", k + 1), o, cases, R);
    R.pass = R.clean == R.untouched &&
             static_cast<double>(R.recovered) >= kSessionRecoveryTarget * static_cast<double>(R.concealed);
    std::ostringstream md;
    md << table(R.rows) << "\nRecovered in " << R.recovered << " of " << R.concealed << " concealed sessions (target "
       << fixed(kSessionRecoveryTarget * 100, 0)
       << " %); untouched sessions claiming nothing new on their own fit: " << R.clean << " of " << R.untouched
       << ".\n";
    write_file((fs::path(staged.path()) / kSessionProofTableFile).string(), md.str());
    staged.commit();
    R.table_path = (fs::path(o.out_dir) / kSessionProofTableFile).string();
    return R;
}

}  // namespace dw::analysis
