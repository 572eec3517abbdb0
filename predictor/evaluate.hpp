#pragma once
// How well a force model predicts: RMSE per axis, and the study's Table 1 metric — the integral
// of |prediction - truth| over the lateral arena at a relative altitude, per axis. Here the arena
// integral is taken over maps: the held-out samples whose neighbours' centroid is within a band
// of the altitude are binned over N-E cells of the 2 m x 2 m arena, prediction and truth are
// averaged per cell (the contour maps people read), and |mean prediction - mean truth| is
// integrated over the occupied cells and divided by their area — an arena-mean error in N or N·m.
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include "predictor/dataset.hpp"
#include "predictor/intervals.hpp"
#include "predictor/model.hpp"

namespace dw::predictor {

struct ArenaOptions {
    double altitude_m = 1.3;    // neighbours' centroid above the sufferer
    double band_m = 0.15;       // ± around it
    double half_width_m = 1.0;  // the arena: |N|, |E| <= this
    double cell_m = 0.1;
};

using flight::AxisValues;

// The model's prediction for one sample of `data` (the physics uses the sample's source's bodies).
Wrench6 predict(const ForceModel& model, const Dataset& data, const Sample& s);

// Over the samples whose source measures the axis (NaN where none does).
AxisValues rmse(const ForceModel& model, const Dataset& data);
// Peak-force error per block (encounter or leg): |max predicted - max recorded| of one axis
// (default f_d, the downwash's push) in each block with a neighbour present, averaged.
struct PeakError {
    double mean_abs = NAN;
    std::size_t blocks = 0;
};
PeakError peak_error(const ForceModel& model, const Dataset& data, int axis = kFdAxis);
// NaN on every axis when no sample falls in the band.
AxisValues arena_error(const ForceModel& model, const Dataset& data, const ArenaOptions& o = {});
// Σ |mean prediction − mean truth| × cell area over the occupied cells (NaN when none is).
AxisValues arena_integral(const ForceModel& model, const Dataset& data, const ArenaOptions& o = {});

struct ComparisonRow {
    std::string formation;
    std::string model;
    std::size_t samples = 0;
    AxisValues arena{};           // Table 1 metric: mean over the occupied cells [N, N·m]
    AxisValues arena_integral{};  // the same |Δ| integrated over the occupied cells [N·m², N·m³]
    AxisValues rmse{};
    double peak_error = NAN;  // f_d, mean over blocks
    std::size_t blocks = 0;
    double coverage_f_d = NAN;  // the share of held-out f_d samples inside the 95 % interval (intervals.hpp)
};

// Every model on every formation of `test` (held-out legs).
// With `noise` (measured on the dataset `test` was cut from: its sources), each row's 95 %
// interval coverage of f_d too.
std::vector<ComparisonRow> compare(const std::vector<const ForceModel*>& models, const Dataset& test,
                                   const ArenaOptions& o = {}, const NoiseModel* noise = nullptr);

// The table as Markdown (arena metric "model a / model b / ..." per formation and axis, then RMSE)
// and as CSV (one row per formation, model, metric).
std::string to_markdown(const std::vector<ComparisonRow>& rows, const ArenaOptions& o);
std::string to_csv(const std::vector<ComparisonRow>& rows, bool header = true);

// Every model on `test`, and the reference row (ReferenceModel: the prediction recorded with the
// flights, reference.csv) over the held-out flights that carry one — all of them ("reference"), or
// some ("reference (K of N flights)", the others named in the note). The rows, what the Markdown
// says of the reference, and whether every held-out flight carries one.
struct Compared {
    std::vector<ComparisonRow> rows;
    std::string reference_note;
    bool reference_everywhere = false;
    std::string noise_note;  // the flights whose interval floor is their jitter (NoiseModel::from_differences)
};
Compared compare_with_reference(const std::vector<const ForceModel*>& models, const Dataset& test,
                                const ArenaOptions& o = {}, const NoiseModel* noise = nullptr);
// What the Markdown says when some flights' poses are the vehicles' own estimates (meta.json
// pose_source: estimate) rather than motion capture; "" when none are.
std::string poses_note(const Dataset& d);

// Throws dw::InputError saying why when `part` (of `all`) holds no sample: never an empty table.
void require_samples(const Dataset& all, const Dataset& part, const std::string& what);

}  // namespace dw::predictor
