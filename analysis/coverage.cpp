#include "analysis/coverage.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <mutex>
#include <optional>
#include <random>
#include <sstream>

#include "analysis/effects.hpp"
#include "analysis/explain.hpp"
#include "analysis/proof.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/parallel.hpp"
#include "flight/flight.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

// An effect hidden in the flights, as its type's coverage case says.
struct Target {
    std::string effect;
    physics::CoverageCase c;
};

// Every registered effect with a coverage case, in the registry's order.
std::vector<Target> targets() {
    std::vector<Target> out;
    for (const auto* t : physics::effect_types())
        if (auto c = t->coverage_case()) out.push_back({t->name(), std::move(*c)});
    return out;
}

std::string covered_names() {
    std::vector<std::string> names;
    for (const auto& t : targets()) names.push_back(t.effect);
    return log::alternatives(names);
}

// The effects without one, and why (for the table).
std::vector<std::pair<std::string, std::string>> not_covered() {
    std::vector<std::pair<std::string, std::string>> out;
    for (const auto* t : physics::effect_types())
        if (!t->coverage_case())
            out.emplace_back(t->name(), t->applies(3, false)
                                            ? "not measured: it has no coverage case"
                                            : "not measured: it acts only on a flying sufferer; the coverage "
                                              "cases fly over the stand");
    return out;
}

// A fraction of flights below this giving an interval at all: the effect is not identifiable from
// such flights (the explainer then claims nothing, rather than a confident wrong value).
constexpr double kMinIdentified = 0.5;

struct Outcome {
    std::vector<double> hidden;  // what the fitted parameters should be (a crosstalk fitted on other axes: 0)
    std::vector<double> values, lo, hi;
    bool interval = false, accepted = false;
};

Outcome one_flight(const Target& t, const Effect& e, int seed, const CoverageOptions& o) {
    std::mt19937_64 rng(static_cast<std::uint64_t>(seed) * 7919 + std::hash<std::string>{}(t.effect) % 7919);
    Outcome out;
    for (const auto& [lo, hi] : t.c.hidden) out.hidden.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
    Effect hide = e;
    if (e.type->has_axes()) hide.from = t.c.axes.from, hide.to = t.c.axes.to;
    physics::PhysicsConfig truth;
    hide.apply(truth, out.hidden);
    const std::string dir = (fs::path(o.out_dir) / t.effect / log::cat("seed_", seed)).string();
    fly_simulated(truth, t.c.formation, 1000 + static_cast<std::uint64_t>(seed), dir + "/flight", o.stop, o.legs);
    ExplainOptions eo;
    eo.candidates = {e};
    eo.max_effects = 1;
    eo.stop = o.stop;
    const auto r = explain(flight::read_flight(dir + "/flight"), eo);
    fs::remove_all(dir + "/flight");  // the flights are made again from their seeds; the outcome is kept below
    const auto& c = r.candidates.front();
    out.values = c.values, out.lo = c.lo, out.hi = c.hi;
    out.interval = c.lo != c.hi;  // the explainer makes an interval only for a fit worth the held-out test
    out.accepted = c.accepted;
    if (e.type->has_axes() && (t.c.axes.from != c.effect.from || t.c.axes.to != c.effect.to))
        out.hidden.assign(out.hidden.size(), 0.0);  // no leak between the axes it chose
    return out;
}

void judge(CoverageRow& r) {
    using V = CoverageRow::Verdict;
    if (r.intervals < kMinIdentified * r.flights) {
        r.verdict = V::not_identifiable;
        r.why = log::cat("not identifiable from these flights: an interval in only ", r.intervals, " of ", r.flights,
                         " (the explainer claims nothing then)");
    } else if (r.coverage() >= kMinCoverage) {
        r.verdict = V::honest;
        r.why = "honest";
    } else {
        r.verdict = V::too_narrow;
        r.why = log::cat("below ", kMinCoverage * 100, " %: the interval is too narrow");
    }
}

CoverageRow row_of(const Target& t, const Effect& e, std::size_t p, const std::vector<Outcome>& outs) {
    CoverageRow r;
    r.effect = t.effect, r.param = e.params[p].name, r.formation = t.c.formation;
    r.drawn = log::cat("U(", t.c.hidden[p].first, ", ", t.c.hidden[p].second, ")");
    double width = 0;
    for (const auto& x : outs) {
        ++r.flights;
        r.accepted += x.accepted ? 1 : 0;
        if (!x.interval) continue;
        ++r.intervals;
        width += (x.hi[p] - x.lo[p]) / 2;
        r.covered += x.hidden[p] >= x.lo[p] && x.hidden[p] <= x.hi[p] ? 1 : 0;
    }
    r.mean_half_width = r.intervals ? width / r.intervals : 0;
    judge(r);
    return r;
}

std::string table(const std::vector<CoverageRow>& rows, const CoverageOptions& o) {
    std::ostringstream md;
    md << "| effect | parameter | formation | hidden value drawn from | flights | with an interval | covered | "
          "coverage | accepted | mean half-width | verdict |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows)
        md << "| " << r.effect << " | " << r.param << " | " << r.formation << " | " << r.drawn << " | " << r.flights
           << " | " << r.intervals << " | " << r.covered << " | "
           << (r.intervals ? fixed(100 * r.coverage(), 0) + " %" : "–") << " | " << r.accepted << " | "
           << fixed(r.mean_half_width, 4) << " | " << r.why << " |\n";
    for (const auto& [name, why] : not_covered())
        md << "| " << name << " | – | – | – | 0 | – | – | – | – | – | " << why << " |\n";
    md << "\n"
       << o.seeds << " flights per effect, " << o.legs
       << " legs each (dw-sim fly, seeds 1000 + k); each explained with the hidden effect as the "
       << "only candidate. Coverage: the share of the intervals made that hold the hidden value (target "
       << kMinCoverage * 100 << " %).\n";
    return md.str();
}

// Every flight's outcome, one row per parameter.
std::string csv(const std::vector<std::pair<Target, Effect>>& chosen, const std::vector<std::vector<Outcome>>& outs) {
    std::ostringstream s;
    s << "effect,parameter,seed,hidden,fitted,lo,hi,interval,accepted\n";
    for (std::size_t ti = 0; ti < chosen.size(); ++ti)
        for (std::size_t k = 0; k < outs[ti].size(); ++k)
            for (std::size_t p = 0; p < chosen[ti].second.params.size(); ++p) {
                const auto& x = outs[ti][k];
                s << CsvRow()
                         .text(chosen[ti].first.effect)
                         .text(chosen[ti].second.params[p].name)
                         .count(static_cast<long long>(k))
                         .num(x.hidden[p])
                         .num(x.values[p])
                         .num(x.lo[p])
                         .num(x.hi[p])
                         .count(x.interval)
                         .count(x.accepted)
                         .line();
            }
    return s.str();
}

}  // namespace

CoverageResult run_coverage(const CoverageOptions& o) {
    std::vector<std::pair<Target, Effect>> chosen;
    for (const auto& t : targets())
        if (o.effects.empty() || std::find(o.effects.begin(), o.effects.end(), t.effect) != o.effects.end())
            chosen.emplace_back(t, effects_named({t.effect}).front());
    for (const auto& n : o.effects)
        if (std::none_of(chosen.begin(), chosen.end(), [&](const auto& c) { return c.first.effect == n; }))
            throw InputError(
                log::cat("--effects: '", n, "' has no coverage run (those with one: ", covered_names(), ")"));
    if (o.seeds < 1) throw InputError("--seeds: at least 1 flight per effect");
    StagedFolder staged(o.out_dir);  // the flights, reports and tables appear together, or not at all
    CoverageOptions in = o;          // every flight and report of the run goes into the staging folder
    in.out_dir = staged.path();
    std::vector<std::vector<Outcome>> outs(chosen.size(), std::vector<Outcome>(static_cast<std::size_t>(o.seeds)));
    std::mutex m;
    const std::size_t total = chosen.size() * static_cast<std::size_t>(o.seeds);
    parallel_for(total, o.jobs, [&](std::size_t k) {
        const auto ti = k / static_cast<std::size_t>(o.seeds), s = k % static_cast<std::size_t>(o.seeds);
        outs[ti][s] = one_flight(chosen[ti].first, chosen[ti].second, static_cast<int>(s), in);
        std::lock_guard lock(m);
        if (o.progress)
            o.progress(log::cat(chosen[ti].first.effect, " seed ", s, ": ",
                                outs[ti][s].interval ? "interval" : "no interval", " (", k + 1, " of ", total, ")"));
    });
    CoverageResult R;
    for (std::size_t ti = 0; ti < chosen.size(); ++ti)
        for (std::size_t p = 0; p < chosen[ti].second.params.size(); ++p)
            R.rows.push_back(row_of(chosen[ti].first, chosen[ti].second, p, outs[ti]));
    R.pass = std::none_of(R.rows.begin(), R.rows.end(),
                          [](const CoverageRow& r) { return r.verdict == CoverageRow::Verdict::too_narrow; });
    write_file((fs::path(in.out_dir) / "coverage.csv").string(), csv(chosen, outs));
    write_file((fs::path(in.out_dir) / kCoverageTableFile).string(), table(R.rows, o));
    staged.commit();
    R.table_path = (fs::path(o.out_dir) / kCoverageTableFile).string();
    return R;
}

}  // namespace dw::analysis
