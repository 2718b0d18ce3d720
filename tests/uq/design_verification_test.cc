// Verification of the designs: Kolmogorov–Smirnov marginals (alpha = 0.01) of Latin hypercube
// and scrambled Sobol' designs (also after the quantile transform), and lower L2 discrepancy
// (Hickernell 1998) of scrambled Sobol' than Monte Carlo at the same N.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "uq/design_checks.h"
#include "uq/distributions.h"
#include "uq/sampling.h"

namespace systole::uq {
namespace {

constexpr double kAlpha = 0.01;

TEST(UqKolmogorovSmirnov, StatisticAndCriticalValueByHand) {
  // Sample {0.1, 0.4, 0.7} vs U(0,1): max over i of (i/3 - x_i, x_i - (i-1)/3)
  // = max(0.2333, 0.1, 0.2667, 0.0667, 0.3, 0.0333) = 0.3.
  EXPECT_NEAR(ks_statistic_uniform(std::vector<double>{0.7, 0.1, 0.4}), 0.3, 1e-15);
  // c(0.01) = sqrt(-ln(0.005) / 2) = 1.62762...; Q(c) = alpha.
  EXPECT_NEAR(ks_critical_value(1, 0.01), 1.6276236, 1e-7);
  // Against the exact Kolmogorov quantile 1.35810 (alpha = 0.05): the first-term formula is
  // 3e-6 higher, i.e. very slightly conservative.
  EXPECT_NEAR(ks_critical_value(100, 0.05), 1.3580986 / 10, 5e-7);
  EXPECT_NEAR(kolmogorov_sf(ks_critical_value(1, 0.01)), 0.01, 2e-9);
  EXPECT_NEAR(kolmogorov_sf(ks_critical_value(1, 0.05)), 0.05, 1e-6);
  // Both series of Q agree where they meet, and Q(0.5) = 0.9639452 (Kolmogorov tables).
  EXPECT_NEAR(kolmogorov_sf(1.1799999), kolmogorov_sf(1.18), 1e-6);
  EXPECT_NEAR(kolmogorov_sf(0.5), 0.9639452, 1e-6);
}

TEST(UqKolmogorovSmirnov, LatinHypercubeMarginalsAreUniform) {
  const std::size_t n = 1000;
  const Matrix m = latin_hypercube(n, 8, 31);
  for (std::size_t c = 0; c < m.cols(); ++c) {
    const double d = ks_statistic_uniform(m.column(c));
    EXPECT_LT(d, ks_critical_value(n, kAlpha)) << "column " << c;
    EXPECT_LE(d, 1.0 / n + 1e-12);  // one point per stratum bounds D_n by 1/n
  }
}

TEST(UqKolmogorovSmirnov, SobolMarginalsAreUniform) {
  for (std::size_t n : {1000u, 1024u}) {
    const Matrix m = sobol(n, kSobolMaxDimensions, 32);
    for (std::size_t c = 0; c < m.cols(); ++c)
      EXPECT_LT(ks_statistic_uniform(m.column(c)), ks_critical_value(n, kAlpha))
          << "n " << n << " column " << c;
  }
}

TEST(UqKolmogorovSmirnov, MappedMarginalsFollowTheirDistributions) {
  const std::vector<Distribution> dists = {
      Distribution::normal(3, 2), Distribution::lognormal(0.5, 0.4),
      Distribution::truncated_normal(1, 1, 0, 2.5), Distribution::uniform(-4, 9)};
  const std::size_t n = 2048;
  for (auto kind : {DesignKind::latin_hypercube, DesignKind::sobol, DesignKind::monte_carlo}) {
    const Matrix x = to_physical(unit_design(kind, n, dists.size(), 33), dists);
    for (std::size_t c = 0; c < dists.size(); ++c) {
      const double d = ks_statistic(x.column(c), [&](double v) { return dists[c].cdf(v); });
      EXPECT_LT(d, ks_critical_value(n, kAlpha)) << to_string(kind) << " " << dists[c].describe();
    }
  }
}

TEST(UqKolmogorovSmirnov, RejectsAWrongMarginal) {
  // The test has power: squared uniforms (CDF sqrt(x)) are far from U(0, 1)
  // (D -> max |sqrt(x) - x| = 1/4, six times the critical value 0.0515 at n = 1000).
  const std::size_t n = 1000;
  std::vector<double> sq = monte_carlo(n, 1, 34).column(0);
  for (double& v : sq) v *= v;
  EXPECT_GT(ks_statistic_uniform(sq), 3 * ks_critical_value(n, kAlpha));
  // ... and accepts them against their true CDF.
  EXPECT_LT(ks_statistic(sq, [](double v) { return std::sqrt(v); }), ks_critical_value(n, kAlpha));
}

TEST(UqDiscrepancy, SinglePointByHand) {
  // One point x = 1/2 in d = 1: CD^2 = 13/12 - 2 (1) + 1 = 1/12; WD^2 = -4/3 + 3/2 = 1/6.
  const Matrix p(1, 1, 0.5);
  EXPECT_NEAR(centered_l2_discrepancy(p), std::sqrt(1.0 / 12.0), 1e-15);
  EXPECT_NEAR(wraparound_l2_discrepancy(p), std::sqrt(1.0 / 6.0), 1e-15);
  // d independent copies multiply: for the point (1/2, 1/2), CD^2 = (13/12)^2 - 2 + 1.
  EXPECT_NEAR(centered_l2_discrepancy(Matrix(1, 2, 0.5)), std::sqrt(169.0 / 144.0 - 1.0), 1e-15);
  EXPECT_THROW(centered_l2_discrepancy(Matrix(1, 1, 1.5)), std::invalid_argument);
}

TEST(UqDiscrepancy, SobolBeatsMonteCarloAtTheSameN) {
  const std::size_t n = 512;
  for (std::size_t d : {2u, 5u, 10u}) {
    for (std::uint64_t seed = 1; seed <= 3; ++seed) {
      const Matrix s = sobol(n, d, seed), m = monte_carlo(n, d, seed);
      const double cs = centered_l2_discrepancy(s), cm = centered_l2_discrepancy(m);
      const double ws = wraparound_l2_discrepancy(s), wm = wraparound_l2_discrepancy(m);
      EXPECT_LT(cs, cm) << "d " << d << " seed " << seed;
      EXPECT_LT(ws, wm) << "d " << d << " seed " << seed;
      if (seed == 1)
        std::printf("N=%zu d=%2zu  CD sobol %.3e  MC %.3e  LHS %.3e | WD sobol %.3e  MC %.3e\n", n,
                    d, cs, cm, centered_l2_discrepancy(latin_hypercube(n, d, seed)), ws, wm);
    }
  }
}

}  // namespace
}  // namespace systole::uq
