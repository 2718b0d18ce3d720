// Designs over the unit hypercube: shapes, ranges, stratification, reproducibility, the raw
// Sobol' sequence against published points, net structure kept by Owen scrambling, and the
// Saltelli layout.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include "uq/random.h"
#include "uq/sampling.h"

namespace systole::uq {
namespace {

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

void expect_open_unit_cube(const Matrix& m) {
  for (double v : m.data()) {
    ASSERT_GT(v, 0.0);
    ASSERT_LT(v, 1.0);
  }
}

TEST(UqRandom, Mt19937_64IsTheStandardOne) {
  // C++ standard [rand.predef]: the 10000th output of a default-constructed mt19937_64.
  Rng rng;
  rng.discard(9999);
  EXPECT_EQ(rng(), 9981545732273789042ULL);
}

TEST(UqRandom, UniformBelowIsUnbiasedAndInRange) {
  Rng rng(7);
  std::vector<int> counts(3, 0);
  for (int i = 0; i < 30000; ++i) ++counts[uniform_below(rng, 3)];
  for (int c : counts) EXPECT_NEAR(c, 10000, 400);  // 4 sigma
  EXPECT_EQ(uniform_below(rng, 1), 0u);
}

TEST(UqDesigns, ShapesAndOpenUnitCube) {
  for (auto kind : {DesignKind::monte_carlo, DesignKind::latin_hypercube, DesignKind::sobol}) {
    const Matrix m = unit_design(kind, 100, 7, 1);
    EXPECT_EQ(m.rows(), 100u);
    EXPECT_EQ(m.cols(), 7u);
    expect_open_unit_cube(m);
  }
}

TEST(UqDesigns, SameSeedSameDesignDifferentSeedDifferentDesign) {
  for (auto kind : {DesignKind::monte_carlo, DesignKind::latin_hypercube, DesignKind::sobol}) {
    const Matrix a = unit_design(kind, 64, 5, 12345);
    const Matrix b = unit_design(kind, 64, 5, 12345);
    const Matrix c = unit_design(kind, 64, 5, 12346);
    EXPECT_EQ(a, b) << to_string(kind);
    std::size_t differ = 0;
    for (std::size_t i = 0; i < a.data().size(); ++i) differ += a.data()[i] != c.data()[i];
    EXPECT_GT(differ, a.data().size() * 9 / 10) << to_string(kind);
  }
  const SaltelliDesign s1 = saltelli(32, 3, 9), s2 = saltelli(32, 3, 9), s3 = saltelli(32, 3, 10);
  EXPECT_EQ(s1.points, s2.points);
  EXPECT_NE(s1.points, s3.points);
}

TEST(UqDesigns, GoldenValuesPinTheStreams) {
  // Designs must not change across platforms or releases: a stored campaign (seed, design)
  // has to regenerate the same inputs. These literals were produced by this implementation.
  EXPECT_EQ(monte_carlo(3, 2, 42)(2, 1), 0x1.e60a14eeb69cep-2);
  EXPECT_EQ(latin_hypercube(5, 2, 42)(4, 1), 0x1.971627aff246ep-1);
  EXPECT_EQ(sobol(8, 3, 42)(7, 2), 0x1.7c98790c747d2p-2);
  EXPECT_EQ(saltelli(4, 2, 42).points(9, 1), 0x1.295aee28f3383p-1);
}

TEST(UqDesigns, ColumnsDoNotDependOnTheNumberOfDimensions) {
  for (auto kind : {DesignKind::monte_carlo, DesignKind::latin_hypercube, DesignKind::sobol}) {
    const Matrix a = unit_design(kind, 50, 2, 3), b = unit_design(kind, 50, 4, 3);
    EXPECT_EQ(a.column(1), b.column(1)) << to_string(kind);
  }
}

TEST(UqDesigns, LatinHypercubeHasOnePointPerStratum) {
  const std::size_t n = 97;
  const Matrix m = latin_hypercube(n, 6, 2024);
  for (std::size_t c = 0; c < m.cols(); ++c) {
    std::set<std::size_t> strata;
    for (std::size_t r = 0; r < n; ++r) strata.insert(static_cast<std::size_t>(m(r, c) * n));
    EXPECT_EQ(strata.size(), n) << "column " << c;
  }
}

TEST(UqSobol, RawSequenceMatchesPublishedPoints) {
  // First 8 points of the 2-D Sobol' sequence with Joe–Kuo direction numbers in Gray-code
  // order (as printed by Joe & Kuo's sobol.cc and SciPy's qmc.Sobol(d=2, scramble=False)).
  const Matrix m = sobol(8, 2, 0, SobolScrambling::none);
  const double x[8][2] = {{0, 0},         {0.5, 0.5},     {0.75, 0.25},  {0.25, 0.75},
                          {0.375, 0.375}, {0.875, 0.875}, {0.625, 0.125}, {0.125, 0.625}};
  for (int i = 0; i < 8; ++i)
    for (int k = 0; k < 2; ++k) EXPECT_EQ(m(i, k), x[i][k]) << i << "," << k;
}

TEST(UqSobol, PropertyAHoldsForTheFirstSixteenDimensions) {
  // Joe & Kuo's direction numbers satisfy Sobol's property A up to dimension 1111: the first
  // 2^d points of the d-dimensional sequence have exactly one point in each of the 2^d
  // half-width sub-cubes. Checked for d = 16 (65536 points). A published property of the data
  // set, independent of this code; it catches some (not all) transcription errors in rows
  // 2..16 of the embedded table, which was also compared line by line with the file.
  const std::size_t d = 16, n = std::size_t{1} << d;
  const Matrix m = sobol(n, d, 0, SobolScrambling::none);
  std::vector<bool> seen(n, false);
  for (std::size_t r = 0; r < n; ++r) {
    std::size_t cell = 0;
    for (std::size_t c = 0; c < d; ++c) cell |= std::size_t{m(r, c) >= 0.5} << c;
    EXPECT_FALSE(seen[cell]) << "row " << r;
    seen[cell] = true;
  }
}

TEST(UqSobol, EveryDimensionIsAOneDimensionalNet) {
  // For n = 2^m, every coordinate of the first n points takes each value k / n exactly once
  // (raw), and each interval [k/n, (k+1)/n) holds exactly one point (scrambled).
  const std::size_t n = 1024;
  for (auto scr : {SobolScrambling::none, SobolScrambling::owen}) {
    const Matrix m = sobol(n, kSobolMaxDimensions, 77, scr);
    for (std::size_t c = 0; c < m.cols(); ++c) {
      std::set<std::size_t> cells;
      for (std::size_t r = 0; r < n; ++r) cells.insert(static_cast<std::size_t>(m(r, c) * n));
      EXPECT_EQ(cells.size(), n) << "dimension " << c;
    }
  }
}

TEST(UqSobol, OwenScramblingKeepsTheTwoDimensionalNetOfTheFirstPair) {
  // Dimensions 1 and 2 of Sobol' form a (0, m, 2)-net for every m: each elementary box of
  // volume 1/n (2^a x 2^(m-a) grid) holds exactly one of the first n = 2^m points. A nested
  // scramble preserves this; a broken scramble would not.
  const unsigned mbits = 8;
  const std::size_t n = std::size_t{1} << mbits;
  const Matrix m = sobol(n, 2, 5);
  for (unsigned a = 0; a <= mbits; ++a) {
    const std::size_t nx = std::size_t{1} << a, ny = n / nx;
    std::set<std::size_t> boxes;
    for (std::size_t r = 0; r < n; ++r)
      boxes.insert(static_cast<std::size_t>(m(r, 0) * nx) * ny + static_cast<std::size_t>(m(r, 1) * ny));
    EXPECT_EQ(boxes.size(), n) << "grid " << nx << " x " << ny;
  }
}

TEST(UqSobol, ScramblingIsNotTheRawSequence) {
  const Matrix raw = sobol(16, 3, 1, SobolScrambling::none);
  const Matrix scr = sobol(16, 3, 1);
  EXPECT_NE(raw(0, 0), scr(0, 0));
  EXPECT_GT(scr(0, 0), 0.0);  // the first raw point (0) is moved inside the cube
}

TEST(UqSaltelli, LayoutIndexingRoundTrips) {
  const SaltelliLayout l(5, 3);
  EXPECT_EQ(l.evaluations(), 25u);
  EXPECT_EQ(l.blocks_per_row(), 5u);
  for (std::size_t e = 0; e < l.evaluations(); ++e) EXPECT_EQ(l.evaluation(l.slot(e)), e);
  EXPECT_EQ(l.slot(0), (SaltelliSlot{0, SaltelliLayout::kBlockA}));
  EXPECT_EQ(l.slot(6), (SaltelliSlot{1, SaltelliLayout::kBlockB}));
  EXPECT_EQ(l.slot(24), (SaltelliSlot{4, SaltelliLayout::block_ab(2)}));
  EXPECT_EQ(l.block_name(0), "A");
  EXPECT_EQ(l.block_name(1), "B");
  EXPECT_EQ(l.block_name(4), "AB_2");
  EXPECT_TRUE(l.is_base_evaluation(5));
  EXPECT_TRUE(l.is_base_evaluation(6));
  EXPECT_FALSE(l.is_base_evaluation(7));
  expect_invalid([&] { l.slot(25); }, {"evaluation = 25", "< 25"});
  expect_invalid([&] { l.evaluation(0, 5); }, {"block = 5", "< 5"});
}

TEST(UqSaltelli, MatricesAreBuiltFromAAndB) {
  for (auto base : {DesignKind::sobol, DesignKind::monte_carlo, DesignKind::latin_hypercube}) {
    const std::size_t n = 16, d = 4;
    const SaltelliDesign s = saltelli(n, d, 3, base);
    ASSERT_EQ(s.points.rows(), n * (d + 2));
    ASSERT_EQ(s.points.cols(), d);
    ASSERT_EQ(s.base.cols(), 2 * d);
    for (std::size_t j = 0; j < n; ++j) {
      for (std::size_t c = 0; c < d; ++c) {
        const double a = s.base(j, c), b = s.base(j, d + c);
        EXPECT_EQ(s.points(s.layout.evaluation(j, SaltelliLayout::kBlockA), c), a);
        EXPECT_EQ(s.points(s.layout.evaluation(j, SaltelliLayout::kBlockB), c), b);
        for (std::size_t i = 0; i < d; ++i)
          EXPECT_EQ(s.points(s.layout.evaluation(j, SaltelliLayout::block_ab(i)), c), i == c ? b : a);
      }
    }
    EXPECT_EQ(s.base, unit_design(base, n, 2 * d, 3));
  }
}

TEST(UqDesigns, InvalidArgumentsNameFieldValueAndRange) {
  expect_invalid([] { monte_carlo(0, 3, 1); }, {"monte_carlo", "samples = 0", ">= 1"});
  expect_invalid([] { latin_hypercube(10, 0, 1); }, {"latin_hypercube", "dimensions = 0"});
  expect_invalid([] { sobol(10, 41, 1); }, {"sobol", "dimensions = 41", "1..40"});
  expect_invalid([] { monte_carlo(std::size_t{1} << 30, 4, 1); }, {"samples * dimensions"});
  expect_invalid([] { saltelli(1, 3, 1); }, {"saltelli", "samples = 1", ">= 2"});
  expect_invalid([] { saltelli(8, 21, 1); }, {"dimensions = 21", "<= 20", "monte_carlo"});
  EXPECT_NO_THROW(saltelli(8, 21, 1, DesignKind::monte_carlo));
  expect_invalid([] { saltelli(8, 2, 1, DesignKind::saltelli); }, {"base design"});
  expect_invalid([] { unit_design(DesignKind::saltelli, 8, 2, 1); }, {"saltelli"});
  expect_invalid([] { parse_design_kind("halton"); }, {"halton", "monte_carlo, latin_hypercube, sobol, saltelli"});
  EXPECT_EQ(parse_design_kind("latin_hypercube"), DesignKind::latin_hypercube);
}

}  // namespace
}  // namespace systole::uq
