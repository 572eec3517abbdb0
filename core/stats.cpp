#include "core/stats.hpp"

#include <algorithm>
#include <array>
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

double t975(int dof) {
    constexpr std::array<double, 10> table{12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228};
    return dof >= 1 && dof <= 10 ? table[static_cast<std::size_t>(dof - 1)] : kZ95 + 2.5 / std::max(dof, 1);
}

namespace {

// The regularised incomplete beta function I_x(a, b) by its continued fraction (modified Lentz),
// on the side where the fraction converges fast.
double incomplete_beta(double x, double a, double b) {
    if (x <= 0) return 0;
    if (x >= 1) return 1;
    if (x > (a + 1) / (a + b + 2)) return 1 - incomplete_beta(1 - x, b, a);
    constexpr double kTiny = 1e-300, kEps = 1e-14;
    constexpr int kMaxTerms = 300;
    const auto guard = [](double v) { return std::abs(v) < kTiny ? kTiny : v; };
    const double front =
        std::exp(std::lgamma(a + b) - std::lgamma(a) - std::lgamma(b) + a * std::log(x) + b * std::log1p(-x)) / a;
    double c = 1, d = 1 / guard(1 - (a + b) * x / (a + 1)), h = d;
    for (int m = 1; m <= kMaxTerms; ++m) {
        const double even = m * (b - m) * x / ((a + 2 * m - 1) * (a + 2 * m));
        d = 1 / guard(1 + even * d), c = guard(1 + even / c), h *= d * c;
        const double odd = -(a + m) * (a + b + m) * x / ((a + 2 * m) * (a + 2 * m + 1));
        d = 1 / guard(1 + odd * d), c = guard(1 + odd / c);
        h *= d * c;
        if (std::abs(d * c - 1) < kEps) break;
    }
    return front * h;
}

}  // namespace

double t_tail_two_sided(double t, int dof) {
    const double nu = std::max(dof, 1);
    return incomplete_beta(nu / (nu + t * t), nu / 2, 0.5);
}

double t_two_sided(double p, int dof) {
    double lo = 0, hi = 1e6;  // the tail falls from 1 at 0; bisect
    for (int k = 0; k < 200 && hi - lo > 1e-9 * hi; ++k) {
        const double mid = 0.5 * (lo + hi);
        (t_tail_two_sided(mid, dof) > p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double normal_upper(double p) {
    double lo = -40, hi = 40;  // the tail falls from 1 to 0; bisect
    for (int k = 0; k < 200 && hi - lo > 1e-12; ++k) {
        const double mid = 0.5 * (lo + hi);
        (0.5 * std::erfc(mid / std::sqrt(2.0)) > p ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

double chi2_upper(double p, int dof) {
    if (dof < 1) return 0;
    const double k = dof, v = 2.0 / (9.0 * k);
    return k * std::pow(std::max(0.0, 1 - v + normal_upper(p) * std::sqrt(v)), 3);
}

std::vector<double> jackknife_sd(const std::vector<std::vector<double>>& replicates) {
    const double G = static_cast<double>(replicates.size());
    std::vector<double> out;
    if (replicates.empty()) return out;
    for (std::size_t p = 0; p < replicates.front().size(); ++p) {
        double mean = 0, var = 0;
        for (const auto& x : replicates) mean += x[p] / G;
        for (const auto& x : replicates) var += (x[p] - mean) * (x[p] - mean);
        out.push_back(std::sqrt(var * (G - 1) / G));
    }
    return out;
}

double median(std::vector<double> v) {
    if (v.empty()) return 0;
    const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    if (v.size() % 2) return *mid;
    return 0.5 * (*mid + *std::max_element(v.begin(), mid));
}

double standard_deviation(std::span<const double> x) {
    if (x.size() < 2) return 0;
    double mean = 0, ss = 0;
    for (const double v : x) mean += v;
    mean /= static_cast<double>(x.size());
    for (const double v : x) ss += (v - mean) * (v - mean);
    return std::sqrt(ss / static_cast<double>(x.size() - 1));
}

double sd_from_differences(std::span<const double> x) {
    if (x.size() < 2) return 0;
    std::vector<double> d;
    d.reserve(x.size() - 1);
    for (std::size_t i = 1; i < x.size(); ++i) d.push_back(std::abs(x[i] - x[i - 1]));
    constexpr double kMadToSd = 1.4826;  // a normal distribution's sd over its median absolute deviation
    return kMadToSd * median(std::move(d)) / std::sqrt(2.0);
}

double huber_cost(double squared, double delta) {
    return squared <= delta * delta ? squared : 2 * delta * std::sqrt(squared) - delta * delta;
}

double ar1_independent_fraction(double rho) { return (1 - rho) / (1 + rho); }

}  // namespace dw
