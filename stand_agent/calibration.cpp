#include "stand_agent/calibration.hpp"

#include <yaml-cpp/yaml.h>

#include <Eigen/Dense>
#include <algorithm>
#include <span>
#include <cmath>
#include <fstream>
#include <sstream>

#include "core/config.hpp"
#include "core/errors.hpp"
#include "core/files.hpp"
#include "core/keys.hpp"
#include "core/log.hpp"
#include "physics/stand.hpp"

namespace dw::stand {

Calibration Calibration::nominal(const physics::StandParams& stand) {
    Calibration c;
    c.counts_per_newton.fill(stand.counts_per_newton);
    c.cell_to_wrench = physics::StandModel(stand).cells_to_wrench();
    return c;
}

physics::Wrench Calibration::wrench(const CellVector& tared) const {
    CellVector forces;
    for (int i = 0; i < kChips; ++i) forces[i] = tared[i] / counts_per_newton[static_cast<std::size_t>(i)];
    return cell_to_wrench * forces;
}

namespace {

constexpr const char* kFormat = "downwash-stand-calibration/1";
constexpr int kAxes = 6;
constexpr Range kGainRange{-1e12, 1e12, "counts/N"};
constexpr Range kMatrixRange{-1e12, 1e12};
using Rows = Eigen::Matrix<double, kAxes, kChips, Eigen::RowMajor>;  // cell_to_wrench as the file lists it

// Every key of a calibration file, declared once (core/keys.hpp).
void calibration_keys(KeyVisitor& k, std::array<double, kChips>& gains, Rows& matrix) {
    k.required_constant("format", kFormat);
    k.require(k.has("counts_per_newton"), "counts_per_newton", "expected a list of 8 numbers");
    k.numbers("counts_per_newton", gains, kGainRange, "expected a list of 8 numbers");
    k.require(std::ranges::none_of(gains, [](double g) { return g == 0; }), "counts_per_newton",
              "expected non-zero numbers");
    const std::string shape = "expected 6 rows (f_n, f_e, f_d, m_roll, m_pitch, m_yaw) of 8 numbers";
    k.require(k.has("cell_to_wrench"), "cell_to_wrench", shape);
    k.table("cell_to_wrench", std::span<double>(matrix.data(), static_cast<std::size_t>(matrix.size())), kChips,
            kMatrixRange, shape);
}

}  // namespace

Calibration Calibration::load(const std::string& path) {
    Calibration c;
    Rows matrix = Rows::Zero();
    read_keys(load_yaml_file(path, "calibration file"), path,
              [&](KeyVisitor& k) { calibration_keys(k, c.counts_per_newton, matrix); });
    c.cell_to_wrench = matrix;
    return c;
}

void Calibration::save(const std::string& path) const {
    auto gains = counts_per_newton;
    Rows matrix = cell_to_wrench;
    YAML::Emitter o;
    o.SetDoublePrecision(12);
    write_keys(o, [&](KeyVisitor& k) { calibration_keys(k, gains, matrix); });
    write_file(path,
               std::string("# Stand calibration: per-cell gain and the cell-to-wrench matrix (rows f_n, f_e, f_d,\n"
                           "# m_roll, m_pitch, m_yaw; columns cells 0-7: 4 vertical, 2 along N, 2 along E).\n") +
                   o.c_str() + "\n");
}

CalibrationFit fit_calibration(const std::vector<KnownLoad>& loads, const std::array<double, kChips>& cpn) {
    if (loads.size() < 6)
        throw InputError(log::cat("calibrate: ", loads.size(), " known loads; at least 6 are needed"));
    const auto n = static_cast<Eigen::Index>(loads.size());
    Eigen::MatrixXd F(kChips, n), W(6, n);
    for (Eigen::Index j = 0; j < n; ++j) {
        for (int i = 0; i < kChips; ++i)
            F(i, j) = loads[static_cast<std::size_t>(j)].tared_counts[i] / cpn[static_cast<std::size_t>(i)];
        W.col(j) = loads[static_cast<std::size_t>(j)].wrench;
    }
    // The loads excite six directions of the eight cell forces (the stand is statically
    // indeterminate); the minimum-norm least-squares solution maps exactly those.
    // A F = W  <=>  F^T A^T = W^T: least squares over the loads.
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(F.transpose(), Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& s = svd.singularValues();
    if (s.size() < 6 || s[5] <= 1e-9 * s[0]) {
        throw InputError("calibrate: the known loads do not excite all six axes (add loads along the missing ones)");
    }
    CalibrationFit out;
    out.condition = s[0] / s[5];
    svd.setThreshold(s[5] / s[0] * 0.5);
    const Eigen::MatrixXd A = svd.solve(W.transpose()).transpose();
    out.calibration.counts_per_newton = cpn;
    out.calibration.cell_to_wrench = A;
    out.residual_rms = std::sqrt((A * F - W).squaredNorm() / static_cast<double>(W.size()));
    return out;
}

std::vector<KnownLoad> read_known_loads(const std::string& path) {
    std::istringstream in(read_file(path, "--loads"));
    std::string line;
    std::getline(in, line);
    const std::string header = "c0,c1,c2,c3,c4,c5,c6,c7,f_n,f_e,f_d,m_roll,m_pitch,m_yaw";
    if (line != header) throw InputError(log::cat(path, ":1: header is '", line, "', expected '", header, "'"));
    std::vector<KnownLoad> loads;
    for (int lineno = 2; std::getline(in, line); ++lineno) {
        if (line.empty()) continue;
        std::stringstream ss(line);
        std::string cell;
        std::vector<double> v;
        while (std::getline(ss, cell, ',')) {
            char* end = nullptr;
            const double x = std::strtod(cell.c_str(), &end);
            if (cell.empty() || *end != '\0' || !std::isfinite(x)) {
                throw InputError(
                    log::cat(path, ":", lineno, ": column ", v.size() + 1, ": '", cell, "' is not a number"));
            }
            v.push_back(x);
        }
        if (v.size() != 14) throw InputError(log::cat(path, ":", lineno, ": ", v.size(), " fields, expected 14"));
        KnownLoad k;
        for (int i = 0; i < kChips; ++i) k.tared_counts[i] = v[static_cast<std::size_t>(i)];
        for (int a = 0; a < 6; ++a) k.wrench[a] = v[static_cast<std::size_t>(8 + a)];
        loads.push_back(k);
    }
    return loads;
}

}  // namespace dw::stand
