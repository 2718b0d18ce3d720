// Input distributions: quantiles against published values, support, moments, validation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "uq/distributions.h"

namespace systole::uq {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Expects std::invalid_argument whose message contains every one of `parts`.
template <class F>
void expect_invalid(F&& f, const std::vector<std::string>& parts) {
  try {
    f();
    ADD_FAILURE() << "no exception";
  } catch (const std::invalid_argument& e) {
    for (const auto& p : parts)
      EXPECT_NE(std::string(e.what()).find(p), std::string::npos) << e.what() << " lacks " << p;
  }
}

TEST(UqStandardNormal, QuantileMatchesTabulatedValues) {
  // Reference values: Abramowitz & Stegun table 26.5 / any 16-digit normal table.
  EXPECT_DOUBLE_EQ(standard_normal_quantile(0.5), 0.0);
  EXPECT_NEAR(standard_normal_quantile(0.975), 1.959963984540054, 1e-14);
  EXPECT_NEAR(standard_normal_quantile(0.025), -1.959963984540054, 1e-14);
  EXPECT_NEAR(standard_normal_quantile(0.95), 1.6448536269514729, 1e-14);
  EXPECT_NEAR(standard_normal_quantile(0.75), 0.6744897501960817, 1e-14);
  EXPECT_NEAR(standard_normal_quantile(0.001), -3.090232306167813, 1e-13);
  EXPECT_NEAR(standard_normal_quantile(1e-10), -6.361340902404056, 1e-12);
  EXPECT_NEAR(standard_normal_quantile(0.8413447460685429), 1.0, 1e-14);
  EXPECT_EQ(standard_normal_quantile(0.0), -kInf);
  EXPECT_EQ(standard_normal_quantile(1.0), kInf);
}

TEST(UqStandardNormal, QuantileInvertsCdfAcrossTheRange) {
  // Lower half through the CDF (for z > 0, p = Phi(z) itself has lost the digits of 1 - p, so
  // the upper half is checked through the survival function below).
  for (double z = -37.0; z <= 0.0; z += 0.25) {
    const double p = standard_normal_cdf(z);
    EXPECT_NEAR(standard_normal_quantile(p), z, 1e-12 * std::max(1.0, std::abs(z))) << z;
  }
  for (double z = 0.5; z <= 37.0; z += 0.5) {  // upper tail through the survival function
    const double q = standard_normal_sf(z);
    EXPECT_NEAR(-standard_normal_quantile(q), z, 1e-12 * z) << z;
  }
}

TEST(UqDistribution, UniformQuantileSupportMoments) {
  const auto d = Distribution::uniform(2.0, 6.0);
  EXPECT_DOUBLE_EQ(d.quantile(0.25), 3.0);
  EXPECT_DOUBLE_EQ(d.quantile(0.0), 2.0);
  EXPECT_DOUBLE_EQ(d.quantile(1.0), 6.0);
  EXPECT_DOUBLE_EQ(d.support().lo, 2.0);
  EXPECT_DOUBLE_EQ(d.support().hi, 6.0);
  EXPECT_DOUBLE_EQ(d.mean(), 4.0);
  EXPECT_DOUBLE_EQ(d.variance(), 16.0 / 12.0);
  EXPECT_DOUBLE_EQ(d.cdf(5.0), 0.75);
  EXPECT_DOUBLE_EQ(d.pdf(5.0), 0.25);
}

TEST(UqDistribution, NormalQuantile) {
  const auto d = Distribution::normal(10.0, 2.0);
  EXPECT_NEAR(d.quantile(0.975), 10.0 + 2.0 * 1.959963984540054, 1e-13);
  EXPECT_DOUBLE_EQ(d.quantile(0.5), 10.0);
  EXPECT_EQ(d.support().lo, -kInf);
  EXPECT_EQ(d.support().hi, kInf);
  EXPECT_DOUBLE_EQ(d.std_dev(), 2.0);
}

TEST(UqDistribution, LognormalQuantileAndMoments) {
  const auto d = Distribution::lognormal(0.0, 1.0);
  EXPECT_NEAR(d.quantile(0.5), 1.0, 1e-15);
  EXPECT_NEAR(d.quantile(0.975), std::exp(1.959963984540054), 1e-12);
  EXPECT_NEAR(d.quantile(0.025), std::exp(-1.959963984540054), 1e-14);
  EXPECT_DOUBLE_EQ(d.support().lo, 0.0);
  EXPECT_EQ(d.support().hi, kInf);
  EXPECT_NEAR(d.mean(), std::exp(0.5), 1e-15);
  EXPECT_NEAR(d.variance(), (std::exp(1.0) - 1.0) * std::exp(1.0), 1e-13);
  const auto e = Distribution::lognormal(std::log(70.0), 0.1);  // median 70
  EXPECT_NEAR(e.quantile(0.5), 70.0, 1e-12);
  EXPECT_GT(e.quantile(1e-300), 0.0);
}

TEST(UqDistribution, TruncatedNormalHalfNormal) {
  // N(0, 1) on [0, inf) is the half-normal: F^-1(u) = Phi^-1((1 + u) / 2),
  // mean sqrt(2/pi), variance 1 - 2/pi.
  const auto d = Distribution::truncated_normal(0.0, 1.0, 0.0, kInf);
  EXPECT_NEAR(d.quantile(0.5), 0.6744897501960817, 1e-14);
  EXPECT_NEAR(d.quantile(0.9), 1.6448536269514729, 1e-13);
  EXPECT_NEAR(d.mean(), std::sqrt(2.0 / std::numbers::pi), 1e-15);
  EXPECT_NEAR(d.variance(), 1.0 - 2.0 / std::numbers::pi, 1e-15);
  EXPECT_DOUBLE_EQ(d.support().lo, 0.0);
  EXPECT_EQ(d.support().hi, kInf);
}

TEST(UqDistribution, TruncatedNormalSymmetricAndRoundTrip) {
  const auto d = Distribution::truncated_normal(5.0, 2.0, 3.0, 7.0);  // +-1 sigma
  EXPECT_NEAR(d.quantile(0.5), 5.0, 1e-14);
  EXPECT_NEAR(d.mean(), 5.0, 1e-14);
  // Variance of N(0,1) on [-1, 1]: 1 - 2 phi(1) / (Phi(1) - Phi(-1)) = 0.29112509...
  const double phi1 = std::exp(-0.5) / std::sqrt(2 * std::numbers::pi);
  const double mass = 0.6826894921370859;
  EXPECT_NEAR(d.variance(), 4.0 * (1.0 - 2.0 * phi1 / mass), 1e-13);
  for (double u = 0.01; u < 1.0; u += 0.01) {
    const double x = d.quantile(u);
    EXPECT_GE(x, 3.0);
    EXPECT_LE(x, 7.0);
    EXPECT_NEAR(d.cdf(x), u, 1e-13);
  }
}

TEST(UqDistribution, TruncatedNormalFarUpperTailKeepsPrecision) {
  // N(0, 1) on [8, inf): mass 6.2e-16, where Phi(8) rounds to 1 in double precision. The
  // median is ~ 8 + ln 2 / 8 (exponential tail approximation).
  const auto d = Distribution::truncated_normal(0.0, 1.0, 8.0, kInf);
  const double median = d.quantile(0.5);
  EXPECT_NEAR(median, 8.0 + std::log(2.0) / 8.0, 3e-3);
  for (double u : {1e-6, 0.1, 0.5, 0.9, 1 - 1e-6}) {
    const double x = d.quantile(u);
    EXPECT_GT(x, 8.0);
    EXPECT_NEAR(d.cdf(x), u, 1e-10) << u;
  }
  // Mills ratio: E[X | X > 8] = phi(8) / Q(8) = 8.1211...
  EXPECT_NEAR(d.mean(), 8.0 + 1.0 / 8.0 - 2.0 / 512.0, 1e-3);
  const auto lower = Distribution::truncated_normal(0.0, 1.0, -kInf, -8.0);
  EXPECT_NEAR(lower.quantile(0.5), -median, 1e-12);
}

TEST(UqDistribution, QuantilesAreMonotoneAndInsideSupport) {
  const std::vector<Distribution> all = {
      Distribution::uniform(-1, 1), Distribution::normal(0, 3), Distribution::lognormal(1, 0.5),
      Distribution::truncated_normal(1, 2, -0.5, 10)};
  for (const auto& d : all) {
    double previous = -kInf;
    for (int i = 1; i < 1000; ++i) {
      const double x = d.quantile(i / 1000.0);
      EXPECT_TRUE(d.support().contains(x)) << d.describe();
      EXPECT_GT(x, previous) << d.describe();
      previous = x;
    }
  }
}

TEST(UqDistribution, SupportWithinFieldRange) {
  EXPECT_TRUE(Distribution::uniform(0.5, 2).support().within(0, 10));
  EXPECT_FALSE(Distribution::uniform(0.5, 20).support().within(0, 10));
  EXPECT_FALSE(Distribution::normal(1, 0.1).support().within(0, kInf));
  EXPECT_TRUE(Distribution::lognormal(1, 0.1).support().within(0, kInf));
  EXPECT_TRUE(Distribution::truncated_normal(1, 0.5, 0.2, kInf).support().within(0, kInf));
}

TEST(UqDistribution, InvalidParametersNameFieldValueAndRange) {
  expect_invalid([] { Distribution::normal(0, -1); }, {"normal", "sigma", "-1", "> 0"});
  expect_invalid([] { Distribution::normal(0, 0); }, {"sigma", "0"});
  expect_invalid([] { Distribution::lognormal(kInf, 1); }, {"lognormal", "mu", "inf", "finite"});
  expect_invalid([] { Distribution::uniform(3, 1); }, {"uniform", "b = 1", "a = 3"});
  expect_invalid([] { Distribution::uniform(0, kInf); }, {"uniform", "b", "inf", "finite"});
  expect_invalid([] { Distribution::truncated_normal(0, 1, 2, 1); }, {"truncated_normal", "b = 1", "a = 2"});
  expect_invalid([] { Distribution::truncated_normal(0, 1, 50, 60); },
                 {"truncated_normal", "[a, b] = [50, 60]", "probability mass"});
  expect_invalid([] { Distribution::truncated_normal(0, 1, std::nan(""), 1); }, {"a = nan"});
  expect_invalid([] { Distribution::normal(0, 1).quantile(1.5); }, {"u = 1.5", "[0, 1]"});
  expect_invalid([] { Distribution::normal(0, 1).quantile(std::nan("")); }, {"u = nan"});
  expect_invalid([] { parse_distribution_kind("gamma"); }, {"gamma", "uniform, normal, lognormal"});
  EXPECT_EQ(parse_distribution_kind("truncated_normal"), DistributionKind::truncated_normal);
}

TEST(UqDistribution, ToPhysicalMapsColumns) {
  Matrix u(2, 2);
  u(0, 0) = 0.25; u(0, 1) = 0.5;
  u(1, 0) = 0.75; u(1, 1) = 0.975;
  const std::vector<Distribution> d = {Distribution::uniform(0, 4), Distribution::normal(1, 1)};
  const Matrix x = to_physical(u, d);
  EXPECT_DOUBLE_EQ(x(0, 0), 1.0);
  EXPECT_DOUBLE_EQ(x(1, 0), 3.0);
  EXPECT_DOUBLE_EQ(x(0, 1), 1.0);
  EXPECT_NEAR(x(1, 1), 1.0 + 1.959963984540054, 1e-14);
  expect_invalid([&] { to_physical(u, std::vector<Distribution>{d[0]}); }, {"2 columns", "1 distributions"});
}

TEST(UqDistribution, MakeFromKindAndParameters) {
  const auto d = Distribution::make(DistributionKind::truncated_normal, std::vector<double>{1, 2, 0, 5});
  EXPECT_EQ(d.parameters(), (std::vector<double>{1, 2, 0, 5}));
  EXPECT_EQ(Distribution::make(parse_distribution_kind("lognormal"), std::vector<double>{0, 1}).kind(),
            DistributionKind::lognormal);
  expect_invalid([] { Distribution::make(DistributionKind::normal, std::vector<double>{1}); },
                 {"normal", "parameter count = 1", "2: mu, sigma"});
}

TEST(UqDistribution, DescribeListsParameters) {
  EXPECT_EQ(Distribution::truncated_normal(1, 0.5, 0, kInf).describe(),
            "truncated_normal(mu=1, sigma=0.5, a=0, b=inf)");
  EXPECT_EQ(Distribution::uniform(1, 2).parameters(), (std::vector<double>{1, 2}));
}

}  // namespace
}  // namespace systole::uq
