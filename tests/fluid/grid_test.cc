// Unit tier: grid geometry, location types, block split, halos.
#include <gtest/gtest.h>

#include <type_traits>

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
