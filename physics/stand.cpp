#include "physics/stand.hpp"

#include <Eigen/Dense>
#include <cmath>

#include "core/errors.hpp"
#include "core/log.hpp"

namespace dw::physics {

StandModel::StandModel(const StandParams& params) {
    const double r = params.lateral_radius_m;
    for (int k = 0; k < 4; ++k) {  // vertical cells under the booms (X configuration)
        const double phi = M_PI / 4 + M_PI / 2 * k;
        cells_[static_cast<std::size_t>(k)] = {r * std::cos(phi), r * std::sin(phi), 2};
    }
    cells_[4] = {0, -r, 0};  // along N, left and right
    cells_[5] = {0, r, 0};
    cells_[6] = {-r, 0, 1};  // along E, behind and in front
    cells_[7] = {r, 0, 1};
    a_.setZero();
    for (int c = 0; c < kCells; ++c) {
        const StandCell& cell = cells_[static_cast<std::size_t>(c)];
        a_(cell.axis, c) = 1.0;
        // torque = r x f for a force along the cell's axis at (x, y, 0)
        if (cell.axis == 2) {
            a_(3, c) = cell.y;
            a_(4, c) = -cell.x;
        } else if (cell.axis == 0) {
            a_(5, c) = -cell.y;
        } else {
            a_(5, c) = cell.x;
        }
    }
    a_pinv_ = a_.completeOrthogonalDecomposition().pseudoInverse();
}

std::int32_t StandModel::to_counts(double force_n, double offset_counts, double counts_per_newton) {
    const double v = std::round(offset_counts + counts_per_newton * force_n);
    if (!std::isfinite(v))
        throw RuntimeError(log::cat("stand model: a non-finite force (", force_n, " N) reached the HX711"));
    if (v >= kCountsMax) return kCountsMax;
    if (v <= kCountsMin) return kCountsMin;
    return static_cast<std::int32_t>(v);
}

}  // namespace dw::physics
