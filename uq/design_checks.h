#pragma once
// Quality checks of designs: the one-sample Kolmogorov–Smirnov test of a marginal and L2-type
// discrepancies of a point set in the unit hypercube.
//
// KS (Kolmogorov 1933, Smirnov 1948): D_n = sup_x |F_n(x) - F(x)|
//   = max_i max( i/n - F(x_(i)), F(x_(i)) - (i - 1)/n ) over the sorted sample.
// Asymptotically P(sqrt(n) D_n > lambda) -> Q(lambda) = 2 sum_{k>=1} (-1)^(k-1) exp(-2 k^2 lambda^2);
// the level-alpha critical value uses the first term, D_crit = sqrt(-ln(alpha/2) / 2) / sqrt(n)
// (alpha = 0.01: 1.6276 / sqrt(n); the neglected terms of the series make it conservative by
// ~1e-9 relative at alpha = 0.01 and 2e-6 at alpha = 0.05).
//
// Discrepancies (Hickernell 1998, "A generalized discrepancy and quadrature error bound",
// Math. Comp. 67, 299-322), for N points x_i in [0, 1]^d:
//   centred L2:     CD^2 = (13/12)^d - (2/N) sum_i prod_k (1 + |x_ik - 1/2|/2 - |x_ik - 1/2|^2/2)
//                          + (1/N^2) sum_i sum_j prod_k (1 + |x_ik - 1/2|/2 + |x_jk - 1/2|/2
//                                                          - |x_ik - x_jk|/2)
//   wrap-around L2: WD^2 = -(4/3)^d + (1/N^2) sum_i sum_j prod_k (3/2 - |x_ik - x_jk| (1 - |x_ik - x_jk|))
// Both functions return the discrepancy (the square root); cost O(N^2 d).
#include <cstddef>
#include <functional>
#include <span>

#include "uq/matrix.h"

namespace systole::uq {

// D_n of `sample` against the continuous CDF `cdf`; non-finite values are not allowed.
double ks_statistic(std::span<const double> sample, const std::function<double(double)>& cdf);
// Against U(0, 1).
double ks_statistic_uniform(std::span<const double> sample);
// Asymptotic critical value of D_n at level alpha in (0, 1), n >= 1.
double ks_critical_value(std::size_t n, double alpha);
// Q(lambda), the asymptotic Kolmogorov survival function (lambda >= 0).
double kolmogorov_sf(double lambda);

// Points are the rows of `points`, all coordinates in [0, 1].
double centered_l2_discrepancy(const Matrix& points);
double wraparound_l2_discrepancy(const Matrix& points);

}  // namespace systole::uq
