#pragma once
// The load stand: 8 load cells — 4 vertical under the booms, 2 along N, 2 along E — the linear map
// between cell forces and the 6-DOF wrench, and the HX711's 24-bit counts.
#include <Eigen/Core>
#include <array>
#include <cstdint>

#include "physics/config.hpp"
#include "physics/wrench_model.hpp"

namespace dw::physics {

inline constexpr int kCells = 8;
inline constexpr std::int32_t kCountsMax = 0x7FFFFF;  // HX711 saturation codes
inline constexpr std::int32_t kCountsMin = -0x800000;

struct StandCell {
    double x = 0, y = 0;  // position in the sufferer's level frame [m]
    int axis = 2;         // the force component it measures: 0 N, 1 E, 2 D
};

class StandModel {
public:
    explicit StandModel(const StandParams& params);
    // wrench = A * cell_forces
    const Eigen::Matrix<double, 6, kCells>& cells_to_wrench() const { return a_; }
    // The minimum-norm cell forces that carry a wrench (the pseudo-inverse of A).
    Eigen::Matrix<double, kCells, 1> wrench_to_cells(const Wrench& w) const { return a_pinv_ * w; }
    const Eigen::Matrix<double, kCells, 6>& wrench_to_cells() const { return a_pinv_; }
    const std::array<StandCell, kCells>& cells() const { return cells_; }

    // What an HX711 reports for a cell force: offset + gain * force, saturated to 24 bits.
    static std::int32_t to_counts(double force_n, double offset_counts, double counts_per_newton);

private:
    std::array<StandCell, kCells> cells_;
    Eigen::Matrix<double, 6, kCells> a_;
    Eigen::Matrix<double, kCells, 6> a_pinv_;
};

}  // namespace dw::physics
