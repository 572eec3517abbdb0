#include "core/stats.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace dw {

double paired_z(std::span<const double> d) {
    std::vector<std::pair<double, double>> ranked;  // |d|, sign
    double sum = 0, sq = 0;
    for (double x : d) {
        if (std::abs(x) > 1e-12) ranked.emplace_back(std::abs(x), x > 0 ? 1.0 : -1.0);
        sum += x;
        sq += x * x;
    }
    std::sort(ranked.begin(), ranked.end());
    double w = 0;
    for (std::size_t k = 0; k < ranked.size(); ++k)
        if (ranked[k].second > 0) w += static_cast<double>(k + 1);
    const double m = static_cast<double>(ranked.size());
    const double ranks = m > 0 ? (w - m * (m + 1) / 4) / std::sqrt(m * (m + 1) * (2 * m + 1) / 24) : 0.0;
    return std::max(ranks, sq > 0 ? sum / std::sqrt(sq) : 0.0);
}

double effective_count(std::span<const double> d) {
    double abs_sum = 0, sq = 0;
    for (double x : d) abs_sum += std::abs(x), sq += x * x;
    return sq > 0 ? abs_sum * abs_sum / sq : 0.0;
}

}  // namespace dw
