#pragma once
// The stand's calibration: per-cell gain (counts per newton) and the cell-to-wrench matrix, in a
// YAML file (downwash-stand-calibration/1); and the least-squares fit of that matrix from
// recorded known loads.
#include <Eigen/Core>
#include <array>
#include <string>
#include <vector>

#include "physics/config.hpp"
#include "physics/wrench_model.hpp"
#include "stand_agent/lines.hpp"

namespace dw::stand {

using CellVector = Eigen::Matrix<double, kChips, 1>;

struct Calibration {
    std::array<double, kChips> counts_per_newton{};
    Eigen::Matrix<double, 6, kChips> cell_to_wrench = Eigen::Matrix<double, 6, kChips>::Zero();

    // The stand's geometry and the load cells' nominal gain.
    static Calibration nominal(const physics::StandParams& stand);
    // Throws dw::InputError naming file, line and key.
    static Calibration load(const std::string& path);
    void save(const std::string& path) const;

    // Tared counts -> wrench [N, N·m].
    physics::Wrench wrench(const CellVector& tared_counts) const;
};

struct KnownLoad {
    CellVector tared_counts;
    physics::Wrench wrench;
};

struct CalibrationFit {
    Calibration calibration;
    double residual_rms = 0;  // over all axes of all loads [N or N·m]
    double condition = 0;     // of the cell forces the loads produced (6 excited directions)
};

// Least squares: the matrix that best maps the cells' forces to the applied wrenches.
// Throws dw::InputError when the loads do not excite all six axes.
CalibrationFit fit_calibration(const std::vector<KnownLoad>& loads,
                               const std::array<double, kChips>& counts_per_newton);
// Reads known loads from CSV: c0..c7 (tared counts), f_n, f_e, f_d, m_roll, m_pitch, m_yaw.
std::vector<KnownLoad> read_known_loads(const std::string& path);

}  // namespace dw::stand
