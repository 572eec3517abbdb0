#include "core/stats.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>
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

namespace {

using Estimates = std::span<const std::pair<double, double>>;

// The inverse-variance mean of estimates with tau2 added to each variance, and its standard error.
std::pair<double, double> pooled_mean(Estimates e, double tau2) {
    double sw = 0, swx = 0;
    for (const auto& [x, v] : e) sw += 1 / (v + tau2), swx += x / (v + tau2);
    return {swx / sw, 1 / std::sqrt(sw)};
}

double cochran_q(Estimates e, double tau2) {
    const double mean = pooled_mean(e, tau2).first;
    double q = 0;
    for (const auto& [x, v] : e) q += (x - mean) * (x - mean) / (v + tau2);
    return q;
}

// Paule-Mandel's spread beyond known2: the tau² that brings Q to dof (Q falls as it grows), by bisection.
constexpr int kSpreadBisections = 60;
double excess_variance(Estimates e, double known2, int dof) {
    if (cochran_q(e, known2) <= dof) return 0;
    double lo = 0, hi = 1;
    while (cochran_q(e, known2 + hi) > dof) hi *= 2;
    for (int k = 0; k < kSpreadBisections; ++k) {
        const double mid = 0.5 * (lo + hi);
        (cochran_q(e, known2 + mid) > dof ? lo : hi) = mid;
    }
    return 0.5 * (lo + hi);
}

}  // namespace

RandomEffects random_effects(Estimates e, double known_sd) {
    RandomEffects r;
    if (e.size() < 2) {
        r.mean = e.empty() ? 0 : e.front().first;
        r.se = r.half95 = INFINITY;
        return r;
    }
    const double known2 = known_sd * known_sd;
    r.dof = static_cast<int>(e.size()) - 1;
    r.q = cochran_q(e, known2);
    const double tau2 = known2 + excess_variance(e, known2, r.dof);
    r.between_sd = std::sqrt(tau2);
    std::tie(r.mean, r.se) = pooled_mean(e, tau2);
    r.half95 = t975(r.dof) * r.se;
    return r;
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
