#include "analysis/proof.hpp"

#include "analysis/conceal.hpp"

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <mutex>
#include <optional>
#include <sstream>

#include "analysis/explain.hpp"
#include "analysis/study.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/names.hpp"
#include "core/numbers.hpp"
#include "core/parallel.hpp"
#include "physics/flight_sim.hpp"
#include "physics/recording_chain.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

// The seed of the flight with two effects at once.
constexpr std::uint64_t kTwoEffectsSeed = 16;

struct Case {
    std::string name, formation, hidden;
    std::function<void(physics::PhysicsConfig&)> hide;
    std::vector<Truth> truth;
    std::uint64_t seed = 1;
};

// The effects that declare a value for it hidden together in one flight (side by side).
Case two_effects_case() {
    Case c{"two_effects", "side_by_side", "", {}, {}, kTwoEffectsSeed};
    std::vector<std::string> said;
    std::vector<std::pair<const physics::EffectType*, std::vector<double>>> hidden;
    for (const auto* t : physics::effect_types())
        if (auto v = t->in_two_effects_case()) {
            hidden.emplace_back(t, *v);
            said.push_back(log::cat(t->name(), " ", log::join(*v, " ")));
            const auto params = t->parameters();
            for (std::size_t k = 0; k < params.size(); ++k) c.truth.push_back({t->name(), params[k].name, (*v)[k], k});
        }
    c.hidden = log::join(said, " and ");
    c.hide = [hidden](physics::PhysicsConfig& config) {
        for (const auto& [t, v] : hidden) t->set(config.effects, v);
    };
    return c;
}

// Every registered effect's own proof case (in the registry's order), then two effects at once.
std::vector<Case> cases() {
    std::vector<Case> out;
    for (const auto* t : physics::effect_types()) {
        auto p = t->proof_case();
        if (!p) continue;
        Case c{t->name(),
               p->formation,
               p->description,
               [t, v = p->values, axes = p->axes](physics::PhysicsConfig& config) { t->set(config.effects, v, axes); },
               {},
               p->seed};
        const auto params = t->parameters();
        for (std::size_t k = 0; k < params.size(); ++k) c.truth.push_back({t->name(), params[k].name, p->values[k], k});
        out.push_back(std::move(c));
    }
    out.push_back(two_effects_case());
    return out;
}

std::vector<std::string> case_names() {
    std::vector<std::string> known{"null"};
    for (const auto& c : cases()) known.push_back(c.name);
    return known;
}

// A truth the explainer did not accept: its fit all the same (is the parameter recovered, only not
// accepted?). Returns whether the flight could not decide it (CandidateResult::too_few_pieces).
bool check_missing(ProofRow& row, const ExplainResult& r, const Truth& t) {
    row.pass = false;
    const auto fit = std::find_if(r.candidates.begin(), r.candidates.end(),
                                  [&](const CandidateResult& c) { return c.effect.name == t.effect; });
    if (fit == r.candidates.end() || fit->lo.size() <= t.index) {
        row.covered = false;
        row.why += t.effect + " not found. ";
        return false;
    }
    const double v = fit->values[t.index], lo = fit->lo[t.index], hi = fit->hi[t.index];
    row.fitted +=
        (row.fitted.empty() ? "" : "; ") + fixed(v, 3) + " [" + fixed(lo, 3) + ", " + fixed(hi, 3) + "] (not accepted)";
    row.covered = row.covered && t.value >= lo && t.value <= hi;
    if (!fit->too_few_pieces) {
        row.why += t.effect + " not found. ";
        return false;
    }
    row.why +=
        log::cat(t.effect, "'s held-out evidence sits in ", fixed(fit->evidence_pieces, 1), " effective pieces. ");
    return true;
}

// A row's verdict: every truth found with its value inside the interval and the held-out error
// reduced, and nothing claimed that was not hidden. A row that fails only because the flight could
// not decide its truths, fitted right, is marked not identifiable.
bool family_named(const ExplainResult& r, const std::vector<Truth>& truth);

void check(ProofRow& row, const ExplainResult& r, const std::vector<Truth>& truth) {
    for (const auto& a : r.accepted) row.found += (row.found.empty() ? "" : ", ") + a.effect.name;
    if (row.found.empty()) row.found = "(none)";
    int missing = 0, undecidable = 0;
    bool other_failure = false;
    for (const auto& t : truth) {
        const auto it = std::find_if(r.accepted.begin(), r.accepted.end(),
                                     [&](const CandidateResult& a) { return a.effect.name == t.effect; });
        row.truth += (row.truth.empty() ? "" : "; ") + t.param + " " + fixed(t.value, 3);
        if (it == r.accepted.end()) {
            ++missing;
            undecidable += check_missing(row, r, t) ? 1 : 0;
            continue;
        }
        const double v = it->values[t.index], lo = it->lo[t.index], hi = it->hi[t.index];
        row.fitted += (row.fitted.empty() ? "" : "; ") + fixed(v, 3) + " [" + fixed(lo, 3) + ", " + fixed(hi, 3) + "]";
        if (t.value < lo || t.value > hi) {
            row.pass = false;
            row.covered = false;
            row.why += t.param + " outside the interval. ";
        }
        const auto ax = static_cast<std::size_t>(it->best_axis);
        row.rmse += (row.rmse.empty() ? "" : "; ") + std::string(flight::kAxes[ax]) + " " +
                    fixed(r.heldout_before[ax], 3) + " → " + fixed(r.heldout_after[ax], 3);
        if (!(r.heldout_after[ax] < r.heldout_before[ax])) {
            row.pass = false;
            other_failure = true;
            row.why += "held-out error not reduced. ";
        }
    }
    for (const auto& a : r.accepted)
        if (std::none_of(truth.begin(), truth.end(), [&](const Truth& t) { return t.effect == a.effect.name; })) {
            row.pass = false;
            other_failure = true;
            row.why += a.effect.name + " claimed but not hidden. ";
        }
    row.not_identifiable = missing > 0 && undecidable == missing && row.covered && !other_failure;
    row.family_named = !row.pass && family_named(r, truth);
}

// Whether every truth not accepted as itself is in a family the report names, and every effect
// accepted but not hidden is a member of such a family.
bool family_named(const ExplainResult& r, const std::vector<Truth>& truth) {
    const auto in_named_family = [&](const std::string& effect, const std::string& with) {
        return std::any_of(r.families.begin(), r.families.end(), [&](const FamilyVerdict& v) {
            const auto has = [&](const std::string& n) {
                return std::find(v.members.begin(), v.members.end(), n) != v.members.end();
            };
            return has(effect) && has(with);
        });
    };
    bool any = false;
    for (const auto& t : truth) {
        if (std::any_of(r.accepted.begin(), r.accepted.end(),
                        [&](const CandidateResult& a) { return a.effect.name == t.effect; }))
            continue;
        const bool named = std::any_of(r.accepted.begin(), r.accepted.end(), [&](const CandidateResult& a) {
            return in_named_family(t.effect, a.effect.name);
        });
        if (!named) return false;
        any = true;
    }
    for (const auto& a : r.accepted)
        if (std::none_of(truth.begin(), truth.end(), [&](const Truth& t) {
                return t.effect == a.effect.name || in_named_family(t.effect, a.effect.name);
            }))
            return false;
    return any;
}

std::string verdict(const ProofRow& r) {
    if (r.pass) return "pass";
    if (r.family_named) return "its family named (this flight cannot tell the members apart): " + r.why;
    return (r.not_identifiable ? "fitted right, not identifiable from this flight: " : "FAIL: ") + r.why;
}

std::string table(const std::vector<ProofRow>& rows, const std::string& flight, const std::string& hidden,
                  const std::string& truth) {
    std::ostringstream md;
    md << "| case | " << flight << " | " << hidden << " | effect found | " << truth
       << " | fitted [95 %] | held-out RMSE before → after | verdict |\n|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
        md << "| " << r.name << " | " << r.formation << " | " << r.hidden << " | " << r.found << " | " << r.truth
           << " | " << r.fitted << " | " << r.rmse << " | " << verdict(r) << " |\n";
    return md.str();
}

}  // namespace

std::string proof_case_list() { return log::join(case_names()); }

void fly_simulated(const physics::PhysicsConfig& hidden, const std::string& formation, std::uint64_t seed,
                   const std::string& dir, const std::stop_token& stop, int legs) {
    fs::create_directories(fs::path(dir).parent_path());
    write_file(dir + ".physics.yaml", physics::to_yaml(hidden));  // what was hidden, beside the flight
    physics::FlyOptions fly;
    fly.formation = formation;
    fly.seed = seed;
    fly.grid.legs = legs;
    fly.stop = stop;
    flight::write_flight(physics::simulate_flight(hidden, fly).flight, dir);
}

namespace {
bool wanted_null(const ProofOptions& o) {
    return o.cases.empty() || std::find(o.cases.begin(), o.cases.end(), "null") != o.cases.end();
}

// One flight of the proof: flown with `hidden` in its air, explained with the plain physics.
ExplainResult fly_and_explain(const physics::PhysicsConfig& hidden, const std::string& formation, std::uint64_t seed,
                              const std::string& dir, const ProofOptions& o) {
    fly_simulated(hidden, formation, seed, dir + "/flight", o.stop);
    ExplainOptions eo;
    eo.physics = physics::PhysicsConfig{};  // what the explainer is given: every effect off
    eo.stop = o.stop;
    const auto f = flight::read_flight(dir + "/flight");
    auto r = explain(f, eo);
    write_report(f, r, eo, dir + "/explain");
    return r;
}

// The proof's flights: each hidden-effect case, then the null flights (seeds 100...).
struct ProofFlight {
    std::optional<Case> c;  // none: a null flight
    int null_index = 0;
};

std::vector<ProofFlight> proof_flights(const ProofOptions& o) {
    std::vector<ProofFlight> out;
    for (const auto& c : cases())
        if (o.cases.empty() || std::find(o.cases.begin(), o.cases.end(), c.name) != o.cases.end())
            out.push_back({c, 0});
    if (wanted_null(o))
        for (int k = 0; k < o.null_seeds; ++k) out.push_back({std::nullopt, k});
    return out;
}

ProofRow null_row(int clean, int total) {
    ProofRow row{"null",
                 "single",
                 "nothing (noise and turbulence only)",
                 log::cat(clean, " of ", total, " seeds claim nothing"),
                 "–",
                 "–",
                 "–",
                 clean * 10 >= total * 9,
                 true,
                 "",
                 0};
    if (!row.pass) row.why = "effects claimed on noise";
    return row;
}
}  // namespace

ProofResult run_proof(const ProofOptions& o) {
    StudyProgress say(o.progress);
    const auto known = case_names();
    require_known_cases(o.cases, known);
    if (wanted_null(o) && o.null_seeds < 1)
        throw InputError("--null-seeds: the null case needs at least 1 flight (or leave it out with --cases)");
    StagedFolder staged(o.out_dir);  // the flights, reports and proof.md appear together, or not at all
    const fs::path out = staged.path();
    const auto flights = proof_flights(o);
    std::vector<ProofRow> rows(flights.size());
    std::vector<char> clean(flights.size(), 0);
    parallel_for(flights.size(), o.jobs, [&](std::size_t i) {
        const auto& pf = flights[i];
        if (!pf.c) {
            const int k = pf.null_index;
            const auto r = fly_and_explain(physics::PhysicsConfig{}, "single", 100 + static_cast<std::uint64_t>(k),
                                           (out / log::cat("null_", k)).string(), o);
            std::string found;
            for (const auto& a : r.accepted) found += (found.empty() ? "" : ", ") + a.effect.name;
            clean[i] = !r.detected;  // clean: nothing claimed, nothing detected
            return say(log::cat("null seed ", 100 + k, ": ", found.empty() ? "nothing claimed" : "claimed " + found,
                                r.detected ? ", detected" : "", " (", r.seconds, " s)"));
        }
        const Case& c = *pf.c;
        physics::PhysicsConfig hidden;
        c.hide(hidden);
        say(log::cat("case ", c.name, ": dw-sim fly --formation ", c.formation, " with ", c.hidden));
        const auto r = fly_and_explain(hidden, c.formation, c.seed, (out / c.name).string(), o);
        ProofRow row{c.name, c.formation, c.hidden, "", "", "", "", true, true, "", r.seconds};
        check(row, r, c.truth);
        say(log::cat("case ", c.name, ": found ", row.found, " (", r.seconds,
                     " s): ", row.pass ? "PASS" : "FAIL " + row.why));
        rows[i] = row;
    });
    ProofResult R;
    for (std::size_t i = 0; i < flights.size(); ++i) {
        if (flights[i].c) R.rows.push_back(rows[i]);
        else ++R.null_total, R.null_clean += clean[i];
    }
    if (R.null_total > 0) R.rows.push_back(null_row(R.null_clean, R.null_total));
    // A proof of nothing proves nothing: no rows, or a null case without flights, fails.
    R.pass = !R.rows.empty() && (!wanted_null(o) || R.null_total > 0) &&
             std::all_of(R.rows.begin(), R.rows.end(), [](const ProofRow& r) { return r.pass; });
    write_file((out / kProofTableFile).string(), table(R.rows, "flight", "hidden effect", "true parameter"));
    staged.commit();
    R.table_path = (fs::path(o.out_dir) / kProofTableFile).string();
    return R;
}

namespace {

// The untouched flight's first fit of an effect (on top of its own fit), if it was scored.
std::optional<double> untouched_value(const ExplainResult& r, const std::string& effect) {
    for (const auto& c : r.candidates)
        if (c.effect.name == effect && !c.values.empty() &&
            on_concealed_axes(*c.effect.type, {c.effect.from, c.effect.to}))
            return c.values.front();
    return std::nullopt;
}

}  // namespace

// Recorded flights are what they are: an effect a flight cannot show (its fit right, its held-out
// evidence in too few pieces) is that flight's verdict, not a failure — but every concealed effect
// must be recovered on some flight.
void require_recovered_somewhere(std::vector<ProofRow>& rows) {
    for (auto& row : rows) {
        const bool recovered =
            std::any_of(rows.begin(), rows.end(), [&](const ProofRow& x) { return x.name == row.name && x.pass; });
        if (row.not_identifiable && !recovered) {
            row.not_identifiable = false;
            row.why += "And it is recovered on no flight of this proof. ";
        }
    }
}

// Why a flight of one vehicle is not proved on.
constexpr const char* kNoNeighbourSkipped = "no neighbour, so no downwash for a concealed effect to act on — skipped";

ProofResult run_real_proof(const RealProofOptions& o) {
    auto say = [&](const std::string& s) {
        if (o.progress) o.progress(s);
    };
    const auto all = concealments(o.concealed);
    for (const auto& n : o.cases)
        if (std::none_of(all.begin(), all.end(), [&](const Concealment& c) { return c.name == n; }))
            throw InputError(log::cat("--cases: unknown case '", n, "' (expected ", concealment_names(), ")"));
    if (o.flights.empty()) throw InputError("--flights: no flight to prove on");
    std::vector<flight::Flight> flights;  // every input read before any output is made
    for (const auto& path : o.flights) flights.push_back(flight::read_flight(path));
    StagedFolder staged(o.out_dir);  // the reports and proof.md appear together, or not at all
    const fs::path out = staged.path();
    ProofResult R;
    for (std::size_t fi = 0; fi < flights.size(); ++fi) {
        const auto& path = o.flights[fi];
        const auto& f = flights[fi];
        const std::string name = fs::path(path).filename().string(), dir = (out / name).string();
        if (f.meta.neighbours.empty()) {
            say(log::cat(name, ": ", kNoNeighbourSkipped));
            R.skipped.push_back(name);
            continue;
        }
        ExplainOptions eo;
        eo.physics = o.physics;
        eo.stop = o.stop;
        say(log::cat(name, ": explaining the untouched flight"));
        const auto own = explain(f, eo);
        write_report(f, own, eo, dir + "/untouched");
        eo.physics = own.fitted;  // from here on, on top of the flight's own fit
        const auto again = explain(f, eo);
        write_report(f, again, eo, dir + "/untouched_on_own_fit");
        std::string own_found;
        for (const auto& a : own.accepted) own_found += (own_found.empty() ? "" : ", ") + a.effect.name;
        ProofRow null_row{"untouched",
                          name,
                          log::cat("nothing (its own fit: ", own_found.empty() ? "no effect" : own_found, ")"),
                          "",
                          "–",
                          "–",
                          "–",
                          true,
                          true,
                          "",
                          again.seconds};
        check(null_row, again, {});
        R.rows.push_back(null_row);
        ++R.null_total;
        R.null_clean += again.accepted.empty() ? 1 : 0;
        say(log::cat("  on its own fit: ", null_row.found, null_row.pass ? " — PASS" : " — FAIL"));
        for (const auto& c : all) {
            if (!o.cases.empty() && std::find(o.cases.begin(), o.cases.end(), c.name) == o.cases.end()) continue;
            flight::Flight hidden = f;
            c.conceal(hidden);
            const auto r = explain(hidden, eo);
            write_report(hidden, r, eo, dir + "/" + c.name);
            ProofRow row{c.name, name, c.description, "", "", "", "", true, true, "", r.seconds};
            check(row, r, {c.expect(own.fitted.effects, untouched_value(again, c.name))});
            say(log::cat("  concealed ", c.name, ": found ", row.found, " (", r.seconds,
                         " s): ", row.pass ? "PASS" : "FAIL " + row.why));
            R.rows.push_back(row);
        }
    }
    require_recovered_somewhere(R.rows);
    R.pass = !R.rows.empty() && std::all_of(R.rows.begin(), R.rows.end(), [](const ProofRow& r) {
        return r.pass || r.not_identifiable || r.family_named;
    });
    std::string skipped;
    if (!R.skipped.empty())
        skipped = log::cat("\nNot proved on (", kNoNeighbourSkipped, "): ", log::join(R.skipped), ".\n");
    write_file((out / kProofTableFile).string(),
               table(R.rows, "flight", "concealed effect", "expected (own fit with the concealed value)") + skipped);
    staged.commit();
    R.table_path = (fs::path(o.out_dir) / kProofTableFile).string();
    return R;
}

}  // namespace dw::analysis
