#pragma once
// The calibration's report: physics.yaml (the base with the calibrated classes), calibration.json,
// calibration.md and one picture per vehicle pairing (recorded, calibrated and uncalibrated f_d by
// the nearest neighbour's position relative to the sufferer).
#include <array>
#include <limits>
#include <string>
#include <vector>

#include "analysis/calibrate.hpp"

namespace dw::analysis {

struct PairingSamples {
    std::string pairing;                      // "32 g, l 92 mm under 67 g, l 120 mm"
    std::vector<std::array<double, 5>> rows;  // the columns below
};
// PairingSamples' columns: the nearest neighbour's horizontal offset and height above [m]; f_d
// recorded, calibrated and from the base (uncalibrated) physics [N].
enum PairingColumn : std::size_t { kOffsetColumn, kAboveColumn, kRecordedColumn, kCalibratedColumn, kBaseColumn };

// What the calibration leaves, by how hard the calibrated physics pushes: the residual's spread
// in bands of |calibrated f_d| [N]. A jet's turbulence (intensity I) scatters a push F by about
// 2 I F, so the spread grows with the force; the least-squares line residual² = a + (2I)² F² says
// how fast (a model of the geometry cannot remove that part: it differs at each pass).
inline constexpr std::array<double, 5> kForceBands_n{0, 0.01, 0.03, 0.06, std::numeric_limits<double>::infinity()};
struct ScatterBand {
    std::size_t n = 0;
    double rms = 0;  // residual (recorded - calibrated, less the pairing's median) [N]
};
struct Scatter {
    std::array<ScatterBand, kForceBands_n.size() - 1> bands{};
    double two_i = 0;  // the line's slope, as 2I (0 when the spread does not grow)
};
Scatter scatter_of(const PairingSamples& p);

// Writes every file into o.out_dir (created); throws dw::RuntimeError when one cannot be written.
void write_calibration(const std::vector<PairingSamples>& pairings, const CalibrateResult& r,
                       const CalibrateOptions& o);

}  // namespace dw::analysis
