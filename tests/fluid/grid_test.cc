// Unit tier: grid geometry, location types, block split, halos.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "solver/core/errors.h"
#include "solver/grid/grid.h"

namespace systole::grid {
namespace {

TEST(Grid, RejectsNonPositiveSizes) {
  EXPECT_THROW(Grid({0, 8, 8, 1, 1, 1}), InputError);
  EXPECT_THROW(Grid({8, 8, 8, 1, -1, 1}), InputError);
  try {
    Grid({8, 8, 1, 1, 1, 1});
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid.nz = 1"), std::string::npos) << e.what();
  }
}

TEST(Grid, CoordinatesFollowTheStaggering) {
  const Grid g({4, 5, 6, 4, 5, 6});
  EXPECT_DOUBLE_EQ(g.x(Location::x_face, 2), 2.0);
  EXPECT_DOUBLE_EQ(g.x(Location::cell, 2), 2.5);
  EXPECT_DOUBLE_EQ(g.y(Location::y_face, 0), 0.0);
  EXPECT_DOUBLE_EQ(g.z(Location::z_face, 6), 6.0);
  EXPECT_DOUBLE_EQ(g.z(Location::x_face, 0), 0.5);
  static_assert(!std::is_convertible_v<XFaceField&, CellField&>, "locations are types");
  static_assert(XFaceField::location == Location::x_face);
}

TEST(Grid, BlockRangesCoverEverythingOnce) {
  int next = 0;
  for (int p = 0; p < 3; ++p) {
    const Range r = block_range(145, 3, p);
    EXPECT_EQ(r.begin, next);
    next += r.count;
  }
  EXPECT_EQ(next, 145);
}

// The split by weight (fsei.slab_split = "balanced"): contiguous, covering, every part non-empty,
// each boundary the one nearest its share of the total; equal weights give equal blocks.
TEST(Grid, WeightedRangesSplitByWeight) {
  auto check_cover = [](const std::vector<Range>& r, int n) {
    int next = 0;
    for (const Range& x : r) {
      EXPECT_EQ(x.begin, next);
      EXPECT_GE(x.count, 1);
      next += x.count;
    }
    EXPECT_EQ(next, n);
  };
  const std::vector<Range> even = weighted_ranges(std::vector<double>(12, 2.5), 3);
  check_cover(even, 12);
  for (const Range& x : even) EXPECT_EQ(x.count, 4);
  // 20 light planes then 10 planes 9x heavier (total 110): halves at 55 -> after plane 23
  // (20 + 3 x 9 = 47) or 24 (56): 24 is nearer
  std::vector<double> heavy(20, 1.0);
  heavy.insert(heavy.end(), 10, 9.0);
  const std::vector<Range> two = weighted_ranges(heavy, 2);
  check_cover(two, 30);
  EXPECT_EQ(two[0].count, 24);
  // all the weight in the first plane: every later part still gets a plane
  std::vector<double> spike(5, 0.0);
  spike[0] = 1;
  const std::vector<Range> four = weighted_ranges(spike, 4);
  check_cover(four, 5);
  EXPECT_EQ(four[0].count, 1);
  EXPECT_THROW(weighted_ranges({1, 1}, 3), std::invalid_argument);
  EXPECT_THROW(weighted_ranges({1, -1, 1}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_ranges({0, 0, 0}, 2), std::invalid_argument);
  EXPECT_THROW(weighted_ranges({1, std::nan(""), 1}, 2), std::invalid_argument);
  const Grid g({4, 3, 6, 1, 1, 1});
  EXPECT_THROW(Slabs(g, MPI_COMM_SELF, {1, 1, 1}), std::invalid_argument);  // not nz weights
}

TEST(Grid, HalosArePeriodicInXAndY) {
  const Grid g({4, 3, 2, 1, 1, 1});
  const Slabs s(g, MPI_COMM_SELF);
  CellField f(s);
  for (int k = 0; k < 2; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 4; ++i) f(i, j, k) = 100 * k + 10 * j + i;
  exchange_halos(f, s);
  EXPECT_EQ(f(-1, 1, 0), f(3, 1, 0));
  EXPECT_EQ(f(4, 2, 1), f(0, 2, 1));
  EXPECT_EQ(f(2, -1, 1), f(2, 2, 1));
  EXPECT_EQ(f(-1, 3, 0), f(3, 0, 0));  // corner
}

}  // namespace
}  // namespace systole::grid
