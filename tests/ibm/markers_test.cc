// Markers from tiled meshes (MODEL.md §4): one per tile with area, normal, velocity and body;
// ΔV = A·h (eq 7); rigid motion; switching a body off; bad input (outside the box, markers
// coarser than the grid, inverted normals).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/markers.h"
#include "solver/geometry/tiling.h"
#include "solver/ibm/shapes.h"

namespace systole::ibm {
namespace {
constexpr double kPi = std::numbers::pi;
const grid::Grid kGrid({20, 20, 20, 2.0, 2.0, 2.0});  // h = 0.1

BodyOptions unit_options(ExpectedNormals n = ExpectedNormals::unchecked) {
  BodyOptions o;
  o.mm_per_unit = 24.0;
  o.normals = n;
  return o;
}

BodyOptions deformable_options() {
  BodyOptions o = unit_options();
  o.rigid = false;
  return o;
}

// The carry-over's anti-windup (ForcingParameters::carry_over_exclusion_cells, ours): the
// markers within r h of another body's marker carry nothing over; exactly those, by brute force.
// Two spheres of diameter 0.5 whose surfaces are 0.1 (one h) apart.
TEST(CarryOverExclusion, MarkersNearAnotherBodyAreExactlyTheExcludedOnes) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  for (double gap_mm : {2.4, 12.0}) {  // 0.1 and 0.5 in grid units (1 h and 5 h)
    Markers m(kGrid);
    m.add_body(sphere_mesh(Vec3(12, 24, 24), 6, 2), "left", unit_options());
    m.add_body(sphere_mesh(Vec3(24 + gap_mm, 24, 24), 6, 2), "right", unit_options());
    for (double cells : {0.0, 2.0, 3.0}) {
      ForcingParameters p;
      p.carry_over = true;
      p.carry_over_exclusion_cells = cells;
      const DirectForcing forcing(slabs, m, p);
      std::size_t near = 0;
      const auto& a = m.markers();
      for (std::size_t i = 0; i < a.size(); ++i)
        for (std::size_t j = 0; j < a.size(); ++j)
          if (a.body[i] != a.body[j] && (a.position[i] - a.position[j]).norm() < cells * m.h()) {
            ++near;
            break;
          }
      std::printf("  [measured] gap %.1f h, exclusion %.0f h: %zu of %zu markers excluded\n", gap_mm / 24 / m.h(),
                  cells, forcing.carry_over_excluded(), m.size());
      EXPECT_EQ(forcing.carry_over_excluded(), near);
      if (gap_mm < 10 && cells >= 2) {
        EXPECT_GT(near, 0u);
        EXPECT_LT(near, m.size() / 2);
      }
      if (gap_mm > 10 || cells == 0) {
        EXPECT_EQ(near, 0u);
      }
    }
  }
  ForcingParameters bad;
  bad.carry_over_exclusion_cells = 5;
  EXPECT_THROW(validate(bad), InputError);
}

// carry_over_exclusion_rigid = false (ours): a rigid body's markers keep their carry-over next to
// another body; the deformable body's markers next to the rigid one are still excluded: exactly
// those, by brute force. The same two spheres one h apart, the left one deformable.
TEST(CarryOverExclusion, ARigidBodyCanKeepItsCarryOver) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  m.add_body(sphere_mesh(Vec3(12, 24, 24), 6, 2), "left", deformable_options());
  m.add_body(sphere_mesh(Vec3(26.4, 24, 24), 6, 2), "right", unit_options());
  ForcingParameters p;
  p.carry_over = true;
  p.carry_over_exclusion_cells = 2;
  const DirectForcing both(slabs, m, p);
  p.carry_over_exclusion_rigid = false;
  const DirectForcing spared(slabs, m, p);
  std::size_t near_left = 0, near_right = 0;
  const auto& a = m.markers();
  for (std::size_t i = 0; i < a.size(); ++i)
    for (std::size_t j = 0; j < a.size(); ++j)
      if (a.body[i] != a.body[j] && (a.position[i] - a.position[j]).norm() < 2 * m.h()) {
        ++(a.body[i] == 0 ? near_left : near_right);
        break;
      }
  ASSERT_GT(near_left, 0u);
  ASSERT_GT(near_right, 0u);
  EXPECT_EQ(both.carry_over_excluded(), near_left + near_right);
  EXPECT_EQ(spared.carry_over_excluded(), near_left);
}

// carry_over_exclusion_rigid_cells (ours): a pair with a rigid body's marker excludes within the
// wider of the two radii, any other pair within carry_over_exclusion_cells: exactly those, by
// brute force. Two deformable spheres one h apart and a rigid one 1.5 h from the first.
TEST(CarryOverExclusion, ARigidBodyCanHaveAWiderRing) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  m.add_body(sphere_mesh(Vec3(12, 24, 24), 6, 2), "left", deformable_options());
  m.add_body(sphere_mesh(Vec3(26.4, 24, 24), 6, 2), "right", deformable_options());
  m.add_body(sphere_mesh(Vec3(19.2, 38, 24), 6, 2), "rigid", unit_options());
  const auto& a = m.markers();
  auto brute_force = [&](double pair_cells, double rigid_cells) {
    std::size_t near = 0;
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < a.size(); ++j) {
        const double cells = a.body[i] == 2 || a.body[j] == 2 ? std::max(pair_cells, rigid_cells) : pair_cells;
        if (a.body[i] != a.body[j] && (a.position[i] - a.position[j]).norm() < cells * m.h()) {
          ++near;
          break;
        }
      }
    return near;
  };
  std::size_t excluded[2] = {0, 0};
  for (int k = 0; k < 2; ++k) {
    ForcingParameters p;
    p.carry_over = true;
    p.carry_over_exclusion_cells = 2;
    p.carry_over_exclusion_rigid_cells = k == 0 ? 0 : 3;  // 0: as any pair
    excluded[k] = DirectForcing(slabs, m, p).carry_over_excluded();
    EXPECT_EQ(excluded[k], brute_force(p.carry_over_exclusion_cells, p.carry_over_exclusion_rigid_cells)) << k;
  }
  std::printf("  [measured] excluded with the rigid ring at 2 h: %zu, at 3 h: %zu of %zu markers\n", excluded[0],
              excluded[1], m.size());
  EXPECT_GT(excluded[1], excluded[0]);  // the wider ring reaches more markers
  // the radius alone, without the pairs' (0 h), still excludes next to the rigid body
  ForcingParameters only_rigid;
  only_rigid.carry_over = true;
  only_rigid.carry_over_exclusion_rigid_cells = 3;
  EXPECT_EQ(DirectForcing(slabs, m, only_rigid).carry_over_excluded(), brute_force(0, 3));
  EXPECT_GT(brute_force(0, 3), 0u);
  ForcingParameters bad;
  bad.carry_over_exclusion_rigid_cells = -1;
  EXPECT_THROW(validate(bad), InputError);
}

// carry_over_exclusion_rigid_wall_cells (ours): a pair of a rigid body's marker and a one-sided
// deformable body's (a wall) excludes within the widest radius; a two-sided deformable body (a
// leaflet) keeps the rigid ring, other pairs the pairs' radius: exactly those, by brute force.
// A wall and a leaflet one h apart, the rigid sphere at the same distance from both.
TEST(CarryOverExclusion, AWallCanHaveAWiderRingThanALeafletNextToARigidBody) {
  const grid::Slabs slabs(kGrid, MPI_COMM_SELF);
  Markers m(kGrid);
  BodyOptions leaflet = deformable_options();
  leaflet.sides = Sides::two;
  m.add_body(sphere_mesh(Vec3(12, 24, 24), 6, 2), "wall", deformable_options());
  m.add_body(sphere_mesh(Vec3(26.4, 24, 24), 6, 2), "leaflet", leaflet);
  m.add_body(sphere_mesh(Vec3(19.2, 38, 24), 6, 2), "rigid", unit_options());
  const auto& a = m.markers();
  // per body of the excluded markers, by brute force
  auto brute_force = [&](double pair_cells, double rigid_cells, double wall_cells) {
    std::array<std::size_t, 3> near{0, 0, 0};
    for (std::size_t i = 0; i < a.size(); ++i)
      for (std::size_t j = 0; j < a.size(); ++j) {
        const bool rigid_pair = a.body[i] == 2 || a.body[j] == 2,
                   wall_pair = rigid_pair && (a.body[i] == 0 || a.body[j] == 0);
        const double cells = wall_pair    ? std::max({pair_cells, rigid_cells, wall_cells})
                             : rigid_pair ? std::max(pair_cells, rigid_cells)
                                          : pair_cells;
        if (a.body[i] != a.body[j] && (a.position[i] - a.position[j]).norm() < cells * m.h()) {
          ++near[static_cast<std::size_t>(a.body[i])];
          break;
        }
      }
    return near;
  };
  auto total = [](const std::array<std::size_t, 3>& n) { return n[0] + n[1] + n[2]; };
  for (const auto& [rigid_cells, wall_cells] : {std::pair{0.0, 0.0}, {0.0, 3.0}, {2.0, 3.0}, {3.0, 2.0}}) {
    ForcingParameters p;
    p.carry_over = true;
    p.carry_over_exclusion_cells = 1.5;
    p.carry_over_exclusion_rigid_cells = rigid_cells;
    p.carry_over_exclusion_rigid_wall_cells = wall_cells;
    const DirectForcing forcing(slabs, m, p);
    const auto expected = brute_force(1.5, rigid_cells, wall_cells);
    EXPECT_EQ(forcing.carry_over_excluded(), total(expected)) << rigid_cells << " " << wall_cells;
    // per body, the code's mask against the brute force's
    std::array<std::size_t, 3> excluded{0, 0, 0};
    for (std::size_t q = 0; q < a.size(); ++q)
      if (!forcing.carries_over(q)) ++excluded[static_cast<std::size_t>(a.body[q])];
    for (std::size_t b = 0; b < 3; ++b) EXPECT_EQ(excluded[b], expected[b]) << rigid_cells << " " << wall_cells << " body " << b;
    // the radii the mask applied: each the widest parameter for its pair
    const auto radii = forcing.carry_over_exclusion_radii();
    EXPECT_EQ(radii.pair_cells, 1.5);
    EXPECT_EQ(radii.rigid_cells, std::max(1.5, rigid_cells));
    EXPECT_EQ(radii.rigid_wall_cells, std::max({1.5, rigid_cells, wall_cells}));
  }
  {
    ForcingParameters p;
    p.carry_over = true;
    p.carry_over_exclusion_cells = 1.5;
    const DirectForcing forcing(slabs, m, p);
    EXPECT_THROW(forcing.carries_over(a.size()), std::out_of_range);
  }
  // pairs at 1.5 h, the rigid ring at 2 h; the walls' at 3 h or as the other rigid pairs'
  const auto as_any = brute_force(1.5, 2, 0), walls = brute_force(1.5, 2, 3);
  std::printf("  [measured] excluded (wall, leaflet, rigid) with a 2-h rigid ring: %zu %zu %zu; walls at 3 h: %zu %zu %zu\n",
              as_any[0], as_any[1], as_any[2], walls[0], walls[1], walls[2]);
  EXPECT_GT(as_any[1], 0u);
  EXPECT_GT(walls[0], as_any[0]);  // the wall's ring reaches further
  EXPECT_EQ(walls[1], as_any[1]);  // the leaflet's does not
  EXPECT_GT(walls[2], as_any[2]);  // the rigid body's markers next to the wall too
  ForcingParameters bad;
  bad.carry_over_exclusion_rigid_wall_cells = 4.5;
  EXPECT_THROW(validate(bad), InputError);
}

TEST(Markers, OneMarkerPerTileWithAreaNormalAndBody) {
  Markers m(kGrid);
  // A sphere of diameter 1 (24 mm) at the box centre; automatic tiling to ≤ 0.7 h.
  const auto mesh = sphere_mesh(Vec3(24, 24, 24), 12, 2);
  const int b = m.add_body(mesh, "sphere", unit_options(ExpectedNormals::outward));
  const Body& body = m.bodies()[b];
  EXPECT_EQ(m.size(), mesh.triangle_count() * body.tiling_level * body.tiling_level);
  double area = 0;
  double worst_normal = 0;
  for (std::size_t q = 0; q < m.size(); ++q) {
    area += m.markers().area[q];
    const Vec3 radial = (m.markers().position[q] - Vec3(1, 1, 1)).normalized();
    worst_normal = std::max(worst_normal, 1 - m.markers().normal[q].dot(radial));
    EXPECT_EQ(m.markers().body[q], b);
    EXPECT_DOUBLE_EQ(m.forcing_volume(q), m.markers().area[q] * m.h());
  }
  // The polyhedron's area is below the sphere's π D² = π (ours: 320 faces → within 2 %).
  std::printf("  [measured] tiling level %d, %zu markers, area %.5f vs π = %.5f\n", body.tiling_level, m.size(), area, kPi);
  EXPECT_NEAR(area, kPi, 0.02 * kPi);
  EXPECT_LT(area, kPi);
  EXPECT_LT(worst_normal, 0.02);
  EXPECT_TRUE(m.warnings().empty());
  EXPECT_LE(geometry::max_edge_mm(body.tiled), 0.7 * m.h() * (1 + 1e-12));
}

TEST(Markers, RigidMotionMovesMarkersAndSetsTheirVelocity) {
  Markers m(kGrid);
  const int b = m.add_body(sphere_mesh(Vec3(24, 24, 24), 6, 1), "sphere", unit_options());
  const Vec3 V(0.1, 0, -0.2), omega(0, 0, 2.0), c(1, 1, 1);
  m.set_rigid_motion(b, V, omega, c);
  const Vec3 x0 = m.markers().position[5];
  for (std::size_t q = 0; q < m.size(); ++q)
    EXPECT_NEAR((m.markers().velocity[q] - (V + omega.cross(m.markers().position[q] - c))).norm(), 0, 1e-14);
  m.advance_rigid(0.25);
  const Vec3 expected = c + V * 0.25 + Eigen::AngleAxisd(0.5, Vec3::UnitZ()) * (x0 - c);
  EXPECT_NEAR((m.markers().position[5] - expected).norm(), 0, 1e-14);
  EXPECT_NEAR((m.bodies()[b].centre - (c + V * 0.25)).norm(), 0, 1e-15);
}

TEST(Markers, BodiesCanBeSwitchedOff) {
  Markers m(kGrid);
  const int plate = m.add_body(plate_with_hole_mesh(0, 0, 48, 24, 6, 3, 16), "plate", unit_options());
  const int cap = m.add_body(sphere_mesh(Vec3(24, 24, 12), 3, 1), "ostium cap", unit_options());
  m.set_active(cap, false);
  for (std::size_t q = 0; q < m.size(); ++q) EXPECT_EQ(m.active(q), m.markers().body[q] == plate);
  m.set_active(cap, true);
  for (std::size_t q = 0; q < m.size(); ++q) EXPECT_TRUE(m.active(q));
}

TEST(MarkersBadInput, MeshOutsideTheBox) {
  Markers m(kGrid);
  try {
    m.add_body(sphere_mesh(Vec3(24, 24, 46), 6, 1), "sphere", unit_options());  // top at z = 52 mm > 45.6
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    std::printf("  [message] %s\n", what.c_str());
    EXPECT_NE(what.find("outside the box"), std::string::npos);
    EXPECT_NE(what.find("sphere"), std::string::npos);
  }
}

TEST(MarkersBadInput, InvertedNormals) {
  Markers m(kGrid);
  auto mesh = sphere_mesh(Vec3(24, 24, 24), 6, 1);
  mesh.flip_orientation();
  try {
    m.add_body(mesh, "sphere", unit_options(ExpectedNormals::outward));
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string what = e.what();
    std::printf("  [message] %s\n", what.c_str());
    EXPECT_NE(what.find("inverted normals"), std::string::npos);
  }
  // The same mesh is right for a body whose blood is inside.
  EXPECT_NO_THROW(m.add_body(mesh, "cavity", unit_options(ExpectedNormals::inward)));
}

TEST(MarkersBadInput, MarkersCoarserThanTheGridWarnWithTheFix) {
  Markers m(kGrid);
  BodyOptions o = unit_options();
  o.tiling_level = 1;  // the icosphere's 0.62-unit edges on a 0.1 grid
  const int b = m.add_body(sphere_mesh(Vec3(24, 24, 24), 12, 1), "coarse sphere", o);
  ASSERT_EQ(m.warnings().size(), 1u);
  std::printf("  [message] %s\n", m.warnings()[0].c_str());
  const int fix = geometry::tiling_level(sphere_mesh(Vec3(24, 24, 24), 12, 1), 0.7 * m.h() * 24);
  EXPECT_NE(m.warnings()[0].find("tiling_level = " + std::to_string(fix)), std::string::npos);
  EXPECT_EQ(m.bodies()[b].tiling_level, 1);
  Markers fixed(kGrid);
  o.tiling_level = fix;
  fixed.add_body(sphere_mesh(Vec3(24, 24, 24), 12, 1), "sphere", o);
  EXPECT_TRUE(fixed.warnings().empty());
}

TEST(MarkersBadInput, BadOptions) {
  Markers m(kGrid);
  BodyOptions o = unit_options();
  o.mm_per_unit = 0;
  EXPECT_THROW(m.add_body(sphere_mesh(Vec3(24, 24, 24), 6, 0), "s", o), InputError);
  o = unit_options();
  o.tiling_level = -1;
  EXPECT_THROW(m.add_body(sphere_mesh(Vec3(24, 24, 24), 6, 0), "s", o), InputError);
  o = unit_options();
  o.retraction_cells = 1.5;
  EXPECT_THROW(m.add_body(sphere_mesh(Vec3(24, 24, 24), 6, 0), "s", o), InputError);
  o = unit_options();
  o.retraction_cells = 0.3;
  o.sides = Sides::two;  // a leaflet has no inside to retract into
  EXPECT_THROW(m.add_body(plate_mesh(12, 12, 12, 12, 24, 2, 2), "leaflet", o), InputError);
}

// The tube's normals point into the lumen (the vessel convention, shapes.h), and the retraction
// (Breugem 2012) moves the forcing points by exactly r_d h away from the blood, leaving the
// surface points (the loads' base) on the tiles.
TEST(Markers, TubeNormalsPointIntoTheLumenAndRetractionMovesOutward) {
  Markers m(kGrid);
  BodyOptions o = unit_options();
  o.mm_per_unit = 1.0;
  o.retraction_cells = 0.3;
  m.add_body(tube_mesh(0, 2, 1, 1, 0.5, 20, 40), "tube", o);
  double worst = 0, worst_shift = 0;
  for (std::size_t q = 0; q < m.size(); ++q) {
    const Vec3& s = m.markers().surface[q];
    const Vec3 radial = Vec3(0, s.y() - 1, s.z() - 1).normalized();
    // n = −e_r up to the facet's tilt at the tile centroid (a triangle of a 40-gon prism)
    worst = std::max(worst, 1 + m.markers().normal[q].dot(radial));
    const Vec3& X = m.markers().position[q];
    EXPECT_NEAR((X - s).norm(), 0.3 * m.h(), 1e-14);
    const double r_surface = std::hypot(s.y() - 1, s.z() - 1), r_force = std::hypot(X.y() - 1, X.z() - 1);
    worst_shift = std::max(worst_shift, std::abs(r_force - r_surface - 0.3 * m.h()) / (0.3 * m.h()));
  }
  EXPECT_LT(worst, 0.01);        // measured 1.4e-3 (3°)
  EXPECT_LT(worst_shift, 0.01);  // measured 1.3e-3 of r_d h
}

}  // namespace
}  // namespace systole::ibm
