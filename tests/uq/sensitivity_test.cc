// Sobol' indices on cases with known answers: a 3-row example computed by hand, an additive
// model (S_i = ST_i = c_i^2 / sum c^2), failed rows dropped and counted, bootstrap seeding.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>
#include <vector>

#include "uq/sensitivity.h"

namespace systole::uq {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::vector<double> evaluate(const SaltelliDesign& s, const std::vector<double>& c) {
  std::vector<double> y(s.points.rows());
  for (std::size_t e = 0; e < y.size(); ++e) {
    double v = 0;
    for (std::size_t i = 0; i < c.size(); ++i) v += c[i] * s.points(e, i);
    y[e] = v;
  }
  return y;
}

TEST(UqSobolIndices, ThreeRowsByHand) {
  // Rows (f_A, f_B, f_AB0): (1, 2, 2), (2, 0, 1), (3, 4, 4).
  // ybar = 12/6 = 2; V = (1 + 0 + 1 + 0 + 4 + 4) / 5 = 2.
  // Centred: fa = (-1, 0, 1), fb = (0, -2, 2), fab = (0, -1, 2).
  // S_0 = (1/3)(0*1 + (-2)(-1) + 2*1) / 2 = 2/3;  ST_0 = (1/6)(1 + 1 + 1) / 2 = 1/4.
  const SaltelliLayout layout(3, 1);
  const std::vector<double> y = {1, 2, 2, 2, 0, 1, 3, 4, 4};
  const SobolIndices r = sobol_indices(layout, y, {.bootstrap_resamples = 0});
  EXPECT_EQ(r.rows_used, 3u);
  EXPECT_DOUBLE_EQ(r.mean, 2.0);
  EXPECT_DOUBLE_EQ(r.variance, 2.0);
  EXPECT_NEAR(r.first_order[0].value, 2.0 / 3.0, 1e-15);
  EXPECT_NEAR(r.total[0].value, 0.25, 1e-15);
  EXPECT_TRUE(std::isnan(r.first_order[0].ci_low));  // no resamples, no interval
  EXPECT_TRUE(r.note.empty());
}

TEST(UqSobolIndices, AdditiveModel) {
  // Y = sum c_i X_i, X_i ~ U(0, 1): S_i = ST_i = c_i^2 / sum c_j^2 = (1, 4, 9, 0) / 14.
  const std::vector<double> c = {1, 2, 3, 0};
  const SaltelliDesign s = saltelli(4096, 4, 11);
  const SobolIndices r = sobol_indices(s.layout, evaluate(s, c), {.bootstrap_resamples = 200});
  for (std::size_t i = 0; i < 4; ++i) {
    const double exact = c[i] * c[i] / 14.0;
    EXPECT_NEAR(r.first_order[i].value, exact, 0.01) << i;
    EXPECT_NEAR(r.total[i].value, exact, 0.01) << i;
    EXPECT_LE(r.first_order[i].ci_low, r.first_order[i].value);
    EXPECT_GE(r.first_order[i].ci_high, r.first_order[i].value);
  }
  EXPECT_NEAR(r.variance, 14.0 / 12.0, 0.01);
  EXPECT_EQ(r.total[3].value, 0.0);  // X_3 has no effect at all: f_A == f_AB3 exactly
}

TEST(UqSobolIndices, FailedEvaluationsDropTheirWholeRow) {
  const std::vector<double> c = {1, 2, 3};
  const std::size_t n = 64, d = 3;
  const SaltelliDesign s = saltelli(n, d, 4);
  std::vector<double> y = evaluate(s, c);
  y[s.layout.evaluation(3, SaltelliLayout::kBlockB)] = kNaN;
  y[s.layout.evaluation(7, SaltelliLayout::kBlockA)] = kNaN;
  y[s.layout.evaluation(7, SaltelliLayout::block_ab(2))] = std::numeric_limits<double>::infinity();
  const SobolIndices r = sobol_indices(s.layout, y, {.bootstrap_resamples = 0});
  EXPECT_EQ(r.rows_total, n);
  EXPECT_EQ(r.rows_used, n - 2);
  EXPECT_EQ(r.rows_dropped, 2u);
  EXPECT_EQ(r.missing_evaluations, 3u);
  EXPECT_EQ(r.dropped_rows, (std::vector<std::size_t>{3, 7}));
  // Same as the design with rows 3 and 7 removed.
  const SaltelliLayout reduced(n - 2, d);
  std::vector<double> kept;
  for (std::size_t j = 0; j < n; ++j)
    if (j != 3 && j != 7)
      for (std::size_t b = 0; b < d + 2; ++b) kept.push_back(y[s.layout.evaluation(j, b)]);
  const SobolIndices ref = sobol_indices(reduced, kept, {.bootstrap_resamples = 0});
  for (std::size_t i = 0; i < d; ++i) {
    EXPECT_DOUBLE_EQ(r.first_order[i].value, ref.first_order[i].value);
    EXPECT_DOUBLE_EQ(r.total[i].value, ref.total[i].value);
  }
  // The std::optional overload gives the same answer.
  std::vector<std::optional<double>> yo(y.begin(), y.end());
  for (std::size_t e = 0; e < y.size(); ++e)
    if (!std::isfinite(y[e])) yo[e] = std::nullopt;
  const SobolIndices ro = sobol_indices(s.layout, yo, {.bootstrap_resamples = 0});
  EXPECT_EQ(ro.missing_evaluations, 3u);
  EXPECT_DOUBLE_EQ(ro.first_order[0].value, r.first_order[0].value);
}

TEST(UqSobolIndices, TooFewRowsOrConstantOutputGiveNaNWithANote) {
  const SaltelliLayout layout(2, 1);
  const SobolIndices one = sobol_indices(layout, std::vector<double>{1, 2, 3, kNaN, 1, 1});
  EXPECT_EQ(one.rows_used, 1u);
  EXPECT_TRUE(std::isnan(one.first_order[0].value));
  EXPECT_NE(one.note.find("only 1 of 2"), std::string::npos) << one.note;
  const SobolIndices flat = sobol_indices(layout, std::vector<double>{5, 5, 5, 5, 5, 5});
  EXPECT_TRUE(std::isnan(flat.total[0].value));
  EXPECT_NE(flat.note.find("constant"), std::string::npos) << flat.note;
}

TEST(UqSobolIndices, BootstrapIsSeeded) {
  const SaltelliDesign s = saltelli(256, 3, 8);
  const std::vector<double> y = evaluate(s, {1, 2, 3});
  const auto a = sobol_indices(s.layout, y, {.bootstrap_resamples = 100, .seed = 1});
  const auto b = sobol_indices(s.layout, y, {.bootstrap_resamples = 100, .seed = 1});
  const auto c = sobol_indices(s.layout, y, {.bootstrap_resamples = 100, .seed = 2});
  EXPECT_EQ(a.first_order[1].ci_low, b.first_order[1].ci_low);
  EXPECT_EQ(a.total[2].ci_high, b.total[2].ci_high);
  EXPECT_NE(a.first_order[1].ci_low, c.first_order[1].ci_low);
  EXPECT_GT(a.first_order[1].std_error, 0.0);
  // A wider confidence level gives a wider interval.
  const auto w = sobol_indices(s.layout, y, {.bootstrap_resamples = 100, .confidence = 0.99, .seed = 1});
  EXPECT_LE(w.first_order[1].ci_low, a.first_order[1].ci_low);
  EXPECT_GE(w.first_order[1].ci_high, a.first_order[1].ci_high);
}

TEST(UqSobolIndices, InvalidArguments) {
  const SaltelliLayout layout(4, 2);
  const std::vector<double> short_y(15, 1.0);
  try {
    sobol_indices(layout, short_y);
    ADD_FAILURE();
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("15 values"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("16 evaluations"), std::string::npos) << e.what();
  }
  const std::vector<double> y(16, 1.0);
  EXPECT_THROW(sobol_indices(layout, y, {.confidence = 1.0}), std::invalid_argument);
  EXPECT_THROW(sobol_indices(layout, y, {.bootstrap_resamples = 2000000}), std::invalid_argument);
}

}  // namespace
}  // namespace systole::uq
