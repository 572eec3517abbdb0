// A session's report: session.json (keys in docs/EXPLAINER.md, "Sessions"), session.md, and each
// flight's own report in a folder of its name.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "analysis/session.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/log.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// A number, or null where it is not finite (a standard error the flight cannot give).
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

json axes_json(const AxisValues& v) {
    json j = json::object();
    for (std::size_t a = 0; a < 6; ++a) j[flight::kAxes[a]] = number(v[a]);
    return j;
}

json heldout_json(const HeldOut& h) {
    return {
        {"axis", flight::kAxes[static_cast<std::size_t>(h.best_axis)]}, {"z", number(h.t)}, {"gain", number(h.gain)}};
}

// Flights like these that would resolve half what the session does (0: none would, or no interval).
std::size_t flights_to_halve(const RigCandidate& c) { return c.flights_to_resolve(c.resolution() / 2); }

json candidate_json(const RigCandidate& c, const std::vector<std::string>& flights) {
    json per = json::array();
    for (std::size_t i = 0; i < c.per_flight.size(); ++i)
        per.push_back({{"flight", flights[i]},
                       {"value", number(c.per_flight[i].value)},
                       {"se", number(c.per_flight[i].se)},
                       {"alone_accepted", c.per_flight[i].alone_accepted}});
    const auto& p = c.effect.params.front();
    const std::size_t halve = flights_to_halve(c);
    json j{{"effect", c.effect.name},
           {"parameter", p.name},
           {"unit", p.unit},
           {"round", c.round},
           {"value", number(c.value)},
           {"interval", {number(c.lo), number(c.hi)}},
           {"resolution", number(c.resolution())},
           {"flights_to_halve", halve ? json(halve) : json(nullptr)},
           {"accepted", c.accepted},
           {"one_value", {{"q", number(c.q)}, {"limit", number(c.q_limit)}, {"dof", c.dof}, {"passed", c.one_value}}},
           {"known_sd", number(c.known_sd)},
           {"between_flight_sd", number(c.between_sd)},
           {"heldout_pooled", heldout_json(c.pooled)},
           {"heldout_flights_left_out", heldout_json(c.left_out)},
           {"alone_accepted", c.alone_count()},
           {"per_flight", per},
           {"family_alike", c.family_alike},
           {"note", c.note}};
    if (c.effect.type->has_axes())
        j["axes"] = {flight::kAxes[static_cast<std::size_t>(c.effect.from)],
                     flight::kAxes[static_cast<std::size_t>(c.effect.to)]};
    return j;
}

json flight_json(const SessionFlightRow& row) {
    json j{{"flight", row.name},
           {"samples", row.samples},
           {"noise_floor", axes_json(row.noise_floor)},
           {"rms_before", axes_json(row.rms_before)},
           {"rms_after", axes_json(row.rms_after)},
           {"own", nullptr}};
    if (row.own) {
        json acc = json::array();
        for (const auto& c : row.own->accepted) acc.push_back({{"effect", c.effect.name}, {"values", c.values}});
        j["own"] = {{"accepted", acc}, {"verdict", verdict_line(*row.own)}, {"report", row.name + "/report.md"}};
    }
    return j;
}

json session_json(const SessionResult& R) {
    json cands = json::array(), rows = json::array(), acc = json::array();
    for (const auto& c : R.candidates) cands.push_back(candidate_json(c, R.flights));
    for (const auto& c : R.accepted) acc.push_back(candidate_json(c, R.flights));
    for (const auto& r : R.rows) rows.push_back(flight_json(r));
    return {{"format", "downwash-session/1"},
            {"flights", R.flights},
            {"rig_candidates", cands},
            {"rig_accepted", acc},
            {"refused_not_one_value", R.refused_not_one_value},
            {"per_flight", rows},
            {"verdict", R.verdict},
            {"seconds", R.seconds}};
}

std::string per_flight_values(const RigCandidate& c) {
    std::vector<std::string> v;
    for (const auto& f : c.per_flight)
        v.push_back(std::isfinite(f.se) ? log::cat(fixed(f.value, 3), " ± ", fixed(f.se, 3)) : fixed(f.value, 3));
    return log::join(v, "; ");
}

void md_rig(std::ostringstream& md, const SessionResult& R) {
    md << "## The rig's effects, fitted over the session\n\n"
       << "Effects of the measurement chain (the sensor's response, the calibration, the stamps' clock) are "
          "one value for every flight a rig flies: fitted jointly, their evidence pooled over the flights' "
          "held-out pieces and over whole flights left out; fitted per flight, values that differ beyond their "
          "spread are not one value and are refused.\n\n"
       << "| round | effect | session value [95 %] | per flight (± s.e.) | one value: Q / 1 % limit | held out, "
          "every flight's pieces: z (gain) | whole flights left out: z | one flight alone accepts it | verdict |\n"
       << "|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : R.candidates)
        md << "| " << c.round << " | " << c.effect.name << " | " << fixed(c.value, 4) << " [" << fixed(c.lo, 4) << ", "
           << fixed(c.hi, 4) << "] " << c.effect.params.front().unit << " | " << per_flight_values(c) << " | "
           << fixed(c.q, 1) << " / " << fixed(c.q_limit, 1) << (c.one_value ? "" : " (not one value)") << " | "
           << fixed(c.pooled.t, 1) << " (" << fixed(c.pooled.gain * 100, 1) << " % of "
           << flight::kAxes[static_cast<std::size_t>(c.pooled.best_axis)] << ") | " << fixed(c.left_out.t, 1) << " | "
           << c.alone_count() << " of " << c.per_flight.size() << " | "
           << (c.accepted        ? "**accepted**"
               : c.not_one_value ? "refused: not one value"
                                 : "not accepted")
           << " |\n";
}

// What the session could have seen: each rig effect's first-round resolution, and the flights a
// smaller one would take (a null verdict is only as good as this).
void md_resolution(std::ostringstream& md, const SessionResult& R) {
    md << "\n## What this session can resolve\n\n"
       << "A rig effect smaller than its resolution (the 95 % interval's half-width, on top of the base physics) "
          "would not be seen here. The flights' values differ by their errors and by nature (the spread between "
          "flights): more flights like these narrow it as t(n - 1) / sqrt(n).\n\n"
       << "| effect | resolved to ± | spread between flights | flights like these to resolve half that |\n"
       << "|---|---|---|---|\n";
    for (const auto& c : R.candidates) {
        if (c.round != 1) continue;
        const std::size_t n = flights_to_halve(c);
        const std::string& unit = c.effect.params.front().unit;
        const std::string u = unit.empty() ? "" : " " + unit;
        md << "| " << c.effect.name << " | " << fixed(c.resolution(), 4) << u << " | " << fixed(c.between_sd, 4) << u
           << " | " << (n ? log::cat(n) : log::cat("more than ", kMaxPlannedFlights, " (or no interval)")) << " |\n";
    }
}

void md_flights(std::ostringstream& md, const SessionResult& R) {
    md << "\n## Per flight\n\n"
       << "| flight | samples | f_d noise floor (N) | f_d RMS residual, before → with the rig's effects (N) | its own "
          "effects, on top of the rig |\n|---|---|---|---|---|\n";
    constexpr std::size_t kFd = 2;
    for (const auto& r : R.rows)
        md << "| " << r.name << " | " << r.samples << " | " << fixed(r.noise_floor[kFd], 4) << " | "
           << fixed(r.rms_before[kFd], 4) << " → " << fixed(r.rms_after[kFd], 4) << " | "
           << (r.own ? log::cat(verdict_line(*r.own), " ([report](", r.name, "/report.md))") : "not explained")
           << " |\n";
}

}  // namespace

std::map<std::string, double> spreads_from(const std::string& path) {
    json j;
    try {
        j = json::parse(read_file(path, "--spread"));
    } catch (const json::exception& e) {
        throw InputError(log::cat(path, ": not JSON (", e.what(), ")"));
    }
    if (!j.is_object() || j.value("format", "") != "downwash-session/1" || !j["rig_candidates"].is_array())
        throw InputError(log::cat(path, ": not a session report (format downwash-session/1 with rig_candidates)"));
    std::map<std::string, double> out;
    for (const auto& c : j["rig_candidates"]) {
        if (!c.is_object() || c.value("round", 0) != 1) continue;
        const auto sd = c.find("between_flight_sd");
        if (sd == c.end() || !sd->is_number() || !std::isfinite(sd->get<double>()) || sd->get<double>() < 0)
            throw InputError(log::cat(path, ": rig_candidates: ", c.value("effect", "?"),
                                      ": between_flight_sd is not a number >= 0"));
        const std::string name = c["effect"].is_string() ? c["effect"].get<std::string>() : "";
        const auto all = all_effects();
        const auto e = std::find_if(all.begin(), all.end(), [&](const Effect& x) { return x.name == name; });
        if (e == all.end()) throw InputError(log::cat(path, ": rig_candidates: unknown effect '", name, "'"));
        Effect x = *e;
        if (x.type->has_axes()) {
            const auto& axes = c["axes"];
            const bool ok = axes.is_array() && axes.size() == 2 && axes[0].is_string() && axes[1].is_string();
            x.from = ok ? physics::axis_index(axes[0].get<std::string>()) : -1;
            x.to = ok ? physics::axis_index(axes[1].get<std::string>()) : -1;
            if (x.from < 0 || x.to < 0)
                throw InputError(
                    log::cat(path, ": rig_candidates: ", name, ": axes is not [from, to] of f_n ... m_yaw"));
        }
        out[spread_key(x)] = sd->get<double>();
    }
    return out;
}

void write_session_report(const std::vector<flight::Flight>& flights, const SessionResult& R, const SessionOptions& o,
                          const std::string& out) {
    StagedFolder staged(out);
    const std::string& dir = staged.path();
    write_file((fs::path(dir) / "session.json").string(), session_json(R).dump(2) + "\n");
    std::ostringstream md;
    md << "# A session of " << R.flights.size() << " flights explained as one\n\n"
       << "**Verdict:** " << R.verdict << ".\n\n";
    md_rig(md, R);
    md_resolution(md, R);
    md_flights(md, R);
    write_file((fs::path(dir) / "session.md").string(), md.str());
    for (std::size_t i = 0; i < R.rows.size(); ++i)
        if (R.rows[i].own) {
            ExplainOptions eo = o.explain;
            eo.physics = R.fitted[i];
            write_report(flights[i], *R.rows[i].own, eo, (fs::path(dir) / R.rows[i].name).string());
        }
    staged.commit();
}

}  // namespace dw::analysis
