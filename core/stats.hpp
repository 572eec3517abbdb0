#pragma once
// Statistics shared by the tools: paired tests over held-out blocks (the explainer: is a candidate
// effect better? the predictor's regime map: is Deep Sets better than the sum?), intervals, and
// the robust summaries the explainer, the calibration and the importer use.
#include <span>
#include <utility>
#include <vector>

namespace dw {

// The evidence that paired differences d (before − after, one per held-out piece) are positive,
// as a normal z: the larger of the Wilcoxon signed-rank z (robust to a few huge pieces, blind to
// their size) and the self-normalised sum Σd/√Σd² (the sign-flip test's z: weighs the pieces by
// how much they gain, so a handful of pieces that gain a lot is evidence while a single one is
// not). Both are ~N(0,1) when the two predict equally well; taking the larger at most doubles the
// chance of a false acceptance. 0 for no pieces.
double paired_z(std::span<const double> d);

// How many of the pieces carry the evidence, counted by weight: (Σ|d|)² / Σd² — n for n equal
// pieces, about 1 when one piece dominates. The self-normalised sum above never exceeds its square
// root, whatever the signs. 0 for no pieces.
double effective_count(std::span<const double> d);

// The two-sided 95 % quantile of the normal distribution (an interval's width in standard errors).
inline constexpr double kZ95 = 1.96;

// Two-sided 95 % quantile of Student's t with dof degrees of freedom (a jackknife's intervals).
double t975(int dof);

// The two-sided tail of Student's t with dof degrees of freedom, P(|T| > t) (from the regularised
// incomplete beta function), and its inverse: the t whose two-sided tail is p (0 < p < 1). A test
// repeated m times at a family-wise level alpha uses t_two_sided(alpha / m, dof) (Bonferroni).
double t_tail_two_sided(double t, int dof);
double t_two_sided(double p, int dof);

// The normal distribution's upper-tail quantile: the z with P(Z > z) = p (0 < p < 1). A one-sided
// test repeated m times at a family-wise level alpha uses normal_upper(alpha / m).
double normal_upper(double p);

// The chi-square distribution's upper-tail quantile: the x with P(X > x) = p for dof degrees of
// freedom (Wilson-Hilferty's cube-root normal approximation: within 1 % of the exact value for
// dof >= 2 at the tails a test uses). 0 for dof < 1.
double chi2_upper(double p, int dof);

// The spread of a jackknife over its replicates (each with one group left out):
// sqrt((G - 1) / G * sum (x - mean)²), per parameter.
std::vector<double> jackknife_sd(const std::vector<std::vector<double>>& replicates);

// Estimates of one quantity pooled as random effects (a meta-analysis of them): each estimate x_i
// with its variance v_i, the true values differing between estimates by a spread tau.
struct RandomEffects {
    double q = 0;             // Cochran's Q about the inverse-variance mean, with the known spread only
    int dof = 0;              // estimates - 1
    double between_sd = 0;    // tau: the known spread and Paule-Mandel's beyond it (Q brought to its dof)
    double mean = 0, se = 0;  // weighed by 1 / (v_i + tau²)
    double half95 = 0;        // Student's t (dof) × se: Hartung-Knapp's 95 % half-width
};
// Fewer than two estimates: dof 0, and the one estimate (or none: 0) with se and half95 infinite.
RandomEffects random_effects(std::span<const std::pair<double, double>> value_variance, double known_sd);

// The median (the mean of the two middle values for an even count); 0 for none.
double median(std::vector<double> v);

// The sample standard deviation of x (n − 1 in the denominator); 0 for fewer than two values.
double standard_deviation(std::span<const double> x);

// The standard deviation of white noise in x, from its successive differences and robustly:
// 1.4826 × median |x[i] − x[i−1]| / √2 (a slow drift or a few spikes do not count). 0 for fewer
// than two values.
double sd_from_differences(std::span<const double> x);

// Huber's loss of a residual r (in units of delta) given as squared = r²: r² within ±delta,
// 2 delta |r| − delta² beyond (continuous, and linear in |r| there).
double huber_cost(double squared, double delta);

// The fraction of n autocorrelated samples that count as independent, for a lag-1 autocorrelation
// rho of an AR(1) series: (1 − rho) / (1 + rho).
double ar1_independent_fraction(double rho);

}  // namespace dw
