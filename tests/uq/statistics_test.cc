// Descriptive statistics against hand-computed small examples; NaN exclusion is counted.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include "uq/statistics.h"

namespace systole::uq {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

TEST(UqPercentiles, Type7LinearInterpolationByHand) {
  // Sorted {1, 2, 3, 4, 10}: h = 4 p. p = .05 -> 1 + .2 (2 - 1) = 1.2; .25 -> 2; .5 -> 3;
  // .75 -> 4; .95 -> h = 3.8 -> 4 + .8 (10 - 4) = 8.8.
  const std::vector<double> v = {10, 3, 1, 4, 2};
  const std::vector<double> p = {5, 25, 50, 75, 95, 0, 100};
  const auto q = percentiles(v, p);
  const std::vector<double> expected = {1.2, 2, 3, 4, 8.8, 1, 10};
  for (std::size_t i = 0; i < p.size(); ++i) EXPECT_NEAR(q[i], expected[i], 1e-12) << p[i];
  // Even n: {1, 2, 3, 4}: h = 3 p: median 2.5, p5 = 1.15, p95 = 3.85.
  const std::vector<double> w = {4, 1, 3, 2};
  const std::vector<double> p2 = {50, 5, 95};
  const auto q2 = percentiles(w, p2);
  EXPECT_NEAR(q2[0], 2.5, 1e-12);
  EXPECT_NEAR(q2[1], 1.15, 1e-12);
  EXPECT_NEAR(q2[2], 3.85, 1e-12);
  EXPECT_THROW(percentiles(w, std::vector<double>{101}), std::invalid_argument);
  EXPECT_THROW(percentiles(std::vector<double>{kNaN}, std::vector<double>{50}), std::invalid_argument);
}

TEST(UqSummary, MeanSampleStdPercentilesAndMissingCount) {
  // Finite values {10, 3, 1, 4, 2}: mean 4, sum of squares 9 + 4 + 1 + 0 + 36 = 50,
  // sample variance 50 / 4 = 12.5. NaN and inf are two failed samples.
  const std::vector<double> y = {10, kNaN, 3, 1, kInf, 4, 2};
  const QoiSummary s = summarize(y);
  EXPECT_EQ(s.total, 7u);
  EXPECT_EQ(s.used, 5u);
  EXPECT_EQ(s.missing, 2u);
  EXPECT_DOUBLE_EQ(s.mean, 4.0);
  EXPECT_NEAR(s.std_dev, std::sqrt(12.5), 1e-14);
  EXPECT_EQ(s.min, 1.0);
  EXPECT_EQ(s.max, 10.0);
  ASSERT_EQ(s.percentiles.size(), 5u);
  EXPECT_EQ(s.percentiles[0].percent, 5.0);
  EXPECT_NEAR(s.percentiles[0].value, 1.2, 1e-12);
  EXPECT_NEAR(s.percentiles[2].value, 3.0, 1e-12);
  EXPECT_NEAR(s.percentiles[4].value, 8.8, 1e-12);
  std::size_t counted = 0;
  for (auto c : s.histogram.counts) counted += c;
  EXPECT_EQ(counted, 5u);
}

TEST(UqSummary, OptionalOverloadTreatsNulloptAsMissing) {
  const std::vector<std::optional<double>> y = {1.0, std::nullopt, 3.0, std::nullopt};
  const QoiSummary s = summarize(y);
  EXPECT_EQ(s.used, 2u);
  EXPECT_EQ(s.missing, 2u);
  EXPECT_DOUBLE_EQ(s.mean, 2.0);
  EXPECT_NEAR(s.std_dev, std::sqrt(2.0), 1e-15);
}

TEST(UqSummary, AllMissingGivesNaNAndCounts) {
  const std::vector<double> y = {kNaN, kNaN};
  const QoiSummary s = summarize(y);
  EXPECT_EQ(s.used, 0u);
  EXPECT_EQ(s.missing, 2u);
  EXPECT_TRUE(std::isnan(s.mean));
  EXPECT_TRUE(std::isnan(s.percentiles[2].value));
  EXPECT_TRUE(s.histogram.counts.empty());
  const QoiSummary one = summarize(std::vector<double>{5.0});
  EXPECT_TRUE(std::isnan(one.std_dev));  // n - 1 = 0
}

TEST(UqHistogram, GivenBins) {
  // {0..4} in 2 bins: [0, 2) holds 0, 1; [2, 4] (last bin closed) holds 2, 3, 4.
  const Histogram h = histogram(std::vector<double>{0, 1, 2, 3, 4, kNaN}, 2);
  EXPECT_EQ(h.rule, "given");
  EXPECT_EQ(h.edges, (std::vector<double>{0, 2, 4}));
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{2, 3}));
}

TEST(UqHistogram, FreedmanDiaconis) {
  // 0..99: IQR = 74.25 - 24.75 = 49.5, h = 2 * 49.5 / 100^(1/3) = 21.33,
  // bins = ceil(99 / 21.33) = 5, each holding 20 values.
  std::vector<double> v;
  for (int i = 0; i < 100; ++i) v.push_back(i);
  const Histogram h = histogram(v);
  EXPECT_EQ(h.rule, "freedman_diaconis");
  EXPECT_EQ(h.counts, (std::vector<std::size_t>{20, 20, 20, 20, 20}));
  EXPECT_DOUBLE_EQ(h.edges.front(), 0.0);
  EXPECT_DOUBLE_EQ(h.edges.back(), 99.0);
  // The cap applies to the automatic rule.
  EXPECT_EQ(histogram(v, 0, 3).counts.size(), 3u);
}

TEST(UqHistogram, DegenerateSamples) {
  // IQR = 0 but a spread: Sturges, ceil(log2 8) + 1 = 4 bins.
  const Histogram s = histogram(std::vector<double>{1, 1, 1, 1, 1, 1, 1, 5});
  EXPECT_EQ(s.rule, "sturges");
  EXPECT_EQ(s.counts, (std::vector<std::size_t>{7, 0, 0, 1}));
  const Histogram c = histogram(std::vector<double>{2, 2, 2});
  EXPECT_EQ(c.rule, "single");
  EXPECT_EQ(c.counts, (std::vector<std::size_t>{3}));
  EXPECT_THROW(histogram(std::vector<double>{1, 2}, 0, 0), std::invalid_argument);
}

TEST(UqCorrelation, PearsonAndSpearmanByHand) {
  // x = 1..5, y = {2, 4, 5, 4, 5}: sxy = 6, sxx = 10, syy = 6 -> r = 6 / sqrt(60).
  // Ranks of y with ties averaged: {1, 2.5, 4.5, 2.5, 4.5}: sxy = 7, syy = 9 -> rho = 7 / sqrt(90).
  const std::vector<double> x = {1, 2, 3, 4, 5}, y = {2, 4, 5, 4, 5};
  EXPECT_NEAR(pearson(x, y), 6.0 / std::sqrt(60.0), 1e-15);
  EXPECT_NEAR(spearman(x, y), 7.0 / std::sqrt(90.0), 1e-15);
  EXPECT_EQ(ranks(y), (std::vector<double>{1, 2.5, 4.5, 2.5, 4.5}));
  // A monotone non-linear relation: Spearman 1, Pearson below 1.
  const std::vector<double> cube = {1, 8, 27, 64, 125};
  EXPECT_NEAR(spearman(x, cube), 1.0, 1e-15);
  EXPECT_LT(pearson(x, cube), 0.99);
  // Constant variable: undefined.
  EXPECT_TRUE(std::isnan(pearson(x, std::vector<double>{3, 3, 3, 3, 3})));
  EXPECT_THROW(pearson(x, std::vector<double>{1, 2}), std::invalid_argument);
}

TEST(UqCorrelation, InputCorrelationsDropPairsWithMissingQoi) {
  Matrix inputs(7, 2);
  const std::vector<double> x = {1, 2, 3, 4, 5, 6, 7};
  for (std::size_t r = 0; r < 7; ++r) {
    inputs(r, 0) = x[r];
    inputs(r, 1) = -x[r];
  }
  const std::vector<double> y = {2, 4, 5, 4, 5, kNaN, kNaN};  // samples 6, 7 failed
  const auto c = input_correlations(inputs, y);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].pairs, 5u);
  EXPECT_NEAR(c[0].pearson, 6.0 / std::sqrt(60.0), 1e-15);
  EXPECT_NEAR(c[0].spearman, 7.0 / std::sqrt(90.0), 1e-15);
  EXPECT_NEAR(c[1].pearson, -6.0 / std::sqrt(60.0), 1e-15);
  EXPECT_NEAR(c[1].spearman, -7.0 / std::sqrt(90.0), 1e-15);
  EXPECT_THROW(input_correlations(inputs, std::vector<double>{1, 2}), std::invalid_argument);
}

}  // namespace
}  // namespace systole::uq
