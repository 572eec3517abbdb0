#include "analysis/calibration_report.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/files.hpp"
#include "core/log.hpp"
#include "core/numbers.hpp"
#include "core/stats.hpp"
#include "physics/config.hpp"
#include "plot/chart.hpp"

namespace dw::analysis {

namespace {

namespace fs = std::filesystem;

// The pictures' grid: the nearest neighbour's horizontal offset and height above the sufferer.
constexpr double kMaxOffset_m = 0.5, kMaxAbove_m = 1.0;
constexpr int kOffsetCells = 10, kAboveCells = 10;
constexpr int kMinPerCell = 5;

std::string pairing_png(std::size_t i) { return log::cat("pairing_", i + 1, ".png"); }

std::string band_name(std::size_t b) {
    return std::isinf(kForceBands_n[b + 1]) ? log::cat("≥ ", kForceBands_n[b])
                                            : log::cat(kForceBands_n[b], "-", kForceBands_n[b + 1]);
}

std::string scatter_section(const std::vector<PairingSamples>& pairings, const std::vector<Scatter>& scatters,
                            double intensity) {
    std::ostringstream md;
    md << "## What is left, by how hard the calibrated physics pushes\n\n"
       << "The residual (recorded − calibrated f_d, less each pairing's median) where a neighbour is near, its "
          "RMS [N] in bands of the calibrated |f_d| [N] (samples in brackets), and 2I from the least-squares line "
          "residual² = a + (2I)² f_d²: a jet whose speed fluctuates by a turbulence intensity I scatters its push "
          "by about 2 I f_d, which no function of where the neighbours are removes.\n\n| pairing |";
    for (std::size_t b = 0; b + 1 < kForceBands_n.size(); ++b) md << " " << band_name(b) << " |";
    md << " 2I |\n|---|";
    for (std::size_t b = 0; b + 1 < kForceBands_n.size(); ++b) md << "---|";
    md << "---|\n";
    for (std::size_t i = 0; i < pairings.size(); ++i) {
        const Scatter& s = scatters[i];
        md << "| " << pairings[i].pairing << " |";
        for (const auto& b : s.bands) md << " " << (b.n ? fixed(b.rms, 4) : std::string("–")) << " (" << b.n << ") |";
        md << " " << fixed(s.two_i, 2) << " |\n";
    }
    md << "\nPooled over every pairing, 2I = " << fixed(2 * intensity, 2)
       << ": the calibrated physics takes a turbulence "
       << "intensity of " << fixed(intensity, 3)
       << " (`turbulence`), which the explainer counts as noise where a jet pushes (its excess divides "
          "each residual by √(σ² + (2 I f_d)²)). Each trial left out gets the intensity of the other trials "
          "(calibration.json, `turbulence_intensity_held_out`).\n\n";
    return md.str();
}

void write_pictures(const std::vector<PairingSamples>& pairings, const std::string& dir) {
    for (std::size_t i = 0; i < pairings.size(); ++i) {
        std::vector<plot::Heat> heats;
        for (const auto& [column, title] : {std::pair{kRecordedColumn, "recorded"},
                                            {kCalibratedColumn, "calibrated"},
                                            {kBaseColumn, "uncalibrated"}}) {
            std::vector<std::array<double, 3>> s;
            for (const auto& r : pairings[i].rows) s.push_back({r[kOffsetColumn], r[kAboveColumn], r[column]});
            heats.push_back(
                plot::bin_heat(title, s, 0, kMaxOffset_m, 0, kMaxAbove_m, kOffsetCells, kAboveCells, kMinPerCell));
        }
        plot::render_heats(heats, "f_d, " + pairings[i].pairing, "nearest neighbour's horizontal offset [m]",
                           "height above the sufferer [m]", "N", (fs::path(dir) / pairing_png(i)).string());
    }
}

nlohmann::json scatter_json(const std::vector<PairingSamples>& pairings, const std::vector<Scatter>& scatters) {
    nlohmann::json out = nlohmann::json::array();
    for (std::size_t i = 0; i < pairings.size(); ++i) {
        const Scatter& s = scatters[i];
        nlohmann::json bands = nlohmann::json::array();
        for (std::size_t b = 0; b < s.bands.size(); ++b)
            bands.push_back(
                {{"calibrated_f_d_from_n", kForceBands_n[b]},
                 {"calibrated_f_d_to_n",
                  std::isinf(kForceBands_n[b + 1]) ? nlohmann::json(nullptr) : nlohmann::json(kForceBands_n[b + 1])},
                 {"samples", s.bands[b].n},
                 {"rms_n", s.bands[b].rms}});
        out.push_back({{"pairing", pairings[i].pairing}, {"bands", bands}, {"two_i", s.two_i}});
    }
    return out;
}

nlohmann::json noise_json(const physics::PredictionNoise& n) {
    return {{"push_share", n.push_share}, {"timing_spread_s", n.timing_spread_s}};
}

nlohmann::json to_json(const CalibrateResult& r) {
    nlohmann::json params = nlohmann::json::array(), trials = nlohmann::json::array();
    for (const auto& p : r.parameters)
        params.push_back({{"class", p.vehicle_class},
                          {"name", p.name},
                          {"unit", p.unit},
                          {"start", p.start},
                          {"value", p.value},
                          {"ci95", {p.lo, p.hi}}});
    for (const auto& t : r.trials)
        trials.push_back({{"trial", t.trial},
                          {"pairing", t.pairing},
                          {"flights", t.flights},
                          {"samples", t.samples},
                          {"rmse_f_d_before_n", t.rmse_before},
                          {"rmse_f_d_all_trials_n", t.rmse_all},
                          {"rmse_f_d_held_out_n", t.rmse_heldout},
                          {"turbulence_intensity_held_out", t.turbulence_intensity},
                          {"prediction_noise_held_out", noise_json(t.noise)},
                          {"standardised_rms_held_out", t.z_rms_heldout},
                          {"explained_f_d_over_noise_floor", t.explained_ratio},
                          {"with_discrepancy_f_d_over_noise_floor", t.discrepancy_ratio},
                          {"explained_by", t.explained_by}});
    nlohmann::json alone = nlohmann::json::array();
    for (const auto& a : r.alone)
        alone.push_back({{"flight", a.flight},
                         {"class", a.vehicle_class},
                         {"samples", a.samples},
                         {"mean_f_d_n", a.mean_f_d},
                         {"rms_f_d_n", a.rms_f_d},
                         {"sd_f_d_n", a.sd_f_d},
                         {"slope_f_d_per_v_d_n_s_per_m", a.slope_per_v_d},
                         {"rms_f_d_after_line_n", a.rms_after_line},
                         {"noise_floor_from_differences_n", a.floor_differences},
                         {"exact_model_f_d_over_that_floor", a.exact_model_ratio()}});
    return {{"format", "downwash-calibration/1"},
            {"calibration", r.calibrated.calibration},
            {"parameters", params},
            {"trials", trials},
            {"alone", alone},
            {"turbulence_intensity", r.turbulence_intensity},
            {"prediction_noise", noise_json(r.calibrated.prediction_noise)},
            {"seconds", r.seconds}};
}

// "2.31 | <effect>, <effect> |" for each of the trial's flights (one line each), their ratios kept.
std::string explained_cells(const TrialError& t, std::vector<double>& ratios, std::vector<double>& with) {
    std::string ratio, learnt, by;
    for (std::size_t k = 0; k < t.explained_ratio.size(); ++k) {
        ratios.push_back(t.explained_ratio[k]);
        with.push_back(t.discrepancy_ratio[k]);
        ratio += (k ? "; " : "") + fixed(t.explained_ratio[k], 2);
        learnt += (k ? "; " : "") + fixed(t.discrepancy_ratio[k], 2);
        by += (k ? "; " : "") + (t.explained_by[k].empty() ? std::string("nothing") : log::join(t.explained_by[k]));
    }
    return ratio + " | " + learnt + " | " + by + " |";
}

// The flights of one vehicle: what the residual does with nobody near (none: nothing).
std::string alone_section(const std::vector<AloneFlight>& alone) {
    if (alone.empty()) return "";
    std::ostringstream md;
    md << "## The residual with nobody near (flights of one vehicle, not in the fit)\n\n"
       << "f_d where no downwash can be (at least " << kAloneMinHeight_m
       << " m above the floor: lower, flights alone may touch it): its mean and RMS, and the least-squares line "
          "against the "
          "sufferer's own vertical velocity (v_d, + descending) — errors of the residual itself, which "
          "the physics cannot be calibrated to remove. Where nobody is ever far (a swap), the explainer's noise "
          "floor is the spread of successive differences: the last two columns are that floor here and the SD "
          "over it, which is what a model exact on every sample would still leave, in such floors.\n\n"
       << "| flight | class | samples | mean f_d [N] | RMS f_d [N] | SD f_d [N] | slope [N per m/s of v_d] | RMS after "
          "the line [N] | successive-difference floor [N] | SD over that floor |\n"
          "|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& a : alone)
        md << "| " << a.flight << " | " << a.vehicle_class << " | " << a.samples << " | " << fixed(a.mean_f_d, 4)
           << " | " << fixed(a.rms_f_d, 4) << " | " << fixed(a.sd_f_d, 4) << " | " << fixed(a.slope_per_v_d, 4) << " | "
           << fixed(a.rms_after_line, 4) << " | " << fixed(a.floor_differences, 4) << " | "
           << fixed(a.exact_model_ratio(), 2) << " |\n";
    md << "\n";
    return md.str();
}

std::string markdown(const std::vector<PairingSamples>& pairings, const std::vector<Scatter>& scatters,
                     const CalibrateResult& r) {
    std::ostringstream md;
    md << "# Calibration\n\n"
       << r.calibrated.calibration << " (" << fixed(r.seconds, 1) << " s).\n\n"
       << "## Parameters (95 % intervals: the leave-one-trial-out jackknife, within each parameter's bounds)\n\n"
       << "| class | parameter | start | calibrated | 95 % interval |\n|---|---|---|---|---|\n";
    for (const auto& p : r.parameters)
        md << "| " << p.vehicle_class << " | " << p.name << (p.unit[0] ? log::cat(" [", p.unit, "]") : "") << " | "
           << fixed(p.start, 4) << " | " << fixed(p.value, 4) << " | [" << fixed(p.lo, 4) << ", " << fixed(p.hi, 4)
           << "] |\n";
    const bool explained = !r.trials.empty() && !r.trials.front().explained_ratio.empty();
    md << "\n## f_d error where a neighbour is near, per trial [N]\n\n"
       << "Held out: the trial predicted by the calibration on every other trial."
       << (explained
               ? " Then explained against that calibration (reports in folds/<trial>/): the explainer's held-out "
                 "f_d error after its effects, in noise floors, then with its learnt discrepancy (what the effects "
                 "leave, as a function of the geometry), and what it accepted."
               : "")
       << "\n\n| trial | pairing | samples | uncalibrated | calibrated on all | held out | held out, standardised "
          "RMS |"
       << (explained ? " after the effects / noise floor | with the discrepancy | explained by "
                       "|\n|---|---|---|---|---|---|---|---|---|---|\n"
                     : "\n|---|---|---|---|---|---|---|\n");
    std::vector<double> before, heldout, ratios, with;
    for (const auto& t : r.trials) {
        md << "| " << t.trial << " | " << t.pairing << " | " << t.samples << " | " << fixed(t.rmse_before, 4) << " | "
           << fixed(t.rmse_all, 4) << " | " << fixed(t.rmse_heldout, 4) << " | " << fixed(t.z_rms_heldout, 2) << " |";
        if (explained) md << " " << explained_cells(t, ratios, with);
        md << "\n";
        before.push_back(t.rmse_before), heldout.push_back(t.rmse_heldout);
    }
    const auto within = std::count_if(r.trials.begin(), r.trials.end(),
                                      [](const TrialError& t) { return kStandardisedBand.contains(t.z_rms_heldout); });
    const auto& n = r.calibrated.prediction_noise;
    md << "\nThe held-out residual standardised by the noise model (each sample over √(floor² + (s p)² + (τ dp/dt)²): "
          "its flight's noise floor — its f_d's spread where the physics predicts no push —, the push p predicted "
          "and its rate, s and τ fitted by maximum likelihood on the other trials; on every trial s = "
       << fixed(n.push_share, 3) << ", τ = " << fixed(n.timing_spread_s, 3)
       << " s, the calibrated physics' `prediction_noise`) has an RMS within [" << kStandardisedBand.lo << ", "
       << kStandardisedBand.hi << "] on " << within << " of " << r.trials.size()
       << " trials (1: the physics and its noise model hold).\n";
    md << "\nMedian over trials: " << fixed(median(before), 4) << " N uncalibrated, " << fixed(median(heldout), 4)
       << " N held out"
       << (explained ? log::cat("; after the explainer, median ", fixed(median(ratios), 2),
                                " noise floors after its effects and ", fixed(median(with), 2),
                                " with its learnt discrepancy (", ratios.size(), " flights)")
                     : std::string())
       << ".\n\n";
    md << alone_section(r.alone) << scatter_section(pairings, scatters, r.turbulence_intensity)
       << "## f_d by the nearest neighbour's position, per pairing\n\n";
    for (std::size_t i = 0; i < pairings.size(); ++i)
        md << "![" << pairings[i].pairing << "](" << pairing_png(i) << ")\n\n";
    return md.str();
}

}  // namespace

Scatter scatter_of(const PairingSamples& p) {
    std::vector<double> residual;
    for (const auto& r : p.rows) residual.push_back(r[kRecordedColumn] - r[kCalibratedColumn]);
    const double zero = residual.empty() ? 0.0 : median(residual);
    Scatter out;
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    for (std::size_t k = 0; k < p.rows.size(); ++k) {
        const double f = std::abs(p.rows[k][kCalibratedColumn]), e = residual[k] - zero;
        for (std::size_t b = 0; b + 1 < kForceBands_n.size(); ++b)
            if (f >= kForceBands_n[b] && f < kForceBands_n[b + 1]) ++out.bands[b].n, out.bands[b].rms += e * e;
        const double x = f * f, y = e * e;
        sx += x, sy += y, sxx += x * x, sxy += x * y;
    }
    for (auto& b : out.bands) b.rms = b.n ? std::sqrt(b.rms / static_cast<double>(b.n)) : 0.0;
    const double n = static_cast<double>(p.rows.size()), var = sxx - sx * sx / n;
    if (n > 2 && var > 0) out.two_i = std::sqrt(std::max(0.0, (sxy - sx * sy / n) / var));
    return out;
}

void write_calibration(const std::vector<PairingSamples>& pairings, const CalibrateResult& r,
                       const CalibrateOptions& o) {
    const fs::path dir(o.out_dir);
    fs::create_directories(dir);
    write_pictures(pairings, o.out_dir);
    std::vector<Scatter> scatters;  // per pairing, for the report and the JSON
    for (const auto& p : pairings) scatters.push_back(scatter_of(p));
    nlohmann::json j = to_json(r);
    j["residual_by_force"] = scatter_json(pairings, scatters);
    write_file((dir / "calibration.json").string(), j.dump(2) + "\n");
    write_file((dir / kCalibrationReportFile).string(), markdown(pairings, scatters, r));
    write_file((dir / kCalibratedPhysicsFile).string(),
               "# " + r.calibrated.calibration + "\n" + physics::to_yaml(r.calibrated));
}

}  // namespace dw::analysis
