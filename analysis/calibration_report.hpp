#pragma once
// The calibration's report: physics.yaml (the base with the calibrated classes), calibration.json,
// calibration.md and one picture per vehicle pairing (recorded, calibrated and uncalibrated f_d by
// the nearest neighbour's position relative to the sufferer).
#include <array>
#include <string>
#include <vector>

#include "analysis/calibrate.hpp"

namespace dw::analysis {

struct PairingSamples {
    std::string pairing;                      // "32 g, l 92 mm under 67 g, l 120 mm"
    std::vector<std::array<double, 5>> rows;  // offset, height above, recorded, calibrated, base f_d [m, m, N, N, N]
};

// Writes every file into o.out_dir (created); throws dw::RuntimeError when one cannot be written.
void write_calibration(const std::vector<PairingSamples>& pairings, const CalibrateResult& r,
                       const CalibrateOptions& o);

}  // namespace dw::analysis
