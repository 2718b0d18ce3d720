// Quadratic tiling: m^2 similar tiles, area and enclosed volume kept exactly, spacing target
// met, attributes inherited, conforming (manifold, oriented) result.
#include <gtest/gtest.h>

#include "solver/config/scenario.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/quality.h"
#include "solver/geometry/summary.h"
#include "solver/geometry/tiling.h"
#include "solver/geometry/topology.h"

namespace systole::geometry {
namespace {

const LeftHeart& default_heart() {
  static const LeftHeart heart = [] {
    const auto s = config::default_scenario();
    return build_left_heart(s.geometry, s.fluid);
  }();
  return heart;
}

TEST(Tiling, KeepsAreaVolumeAndAttributes) {
  const LeftHeart& heart = default_heart();
  const TriMesh& lv = heart.body(kLvBody);
  for (int m : {2, 3, 5}) {
    const TriMesh t = tile(lv, m);
    ASSERT_EQ(t.triangle_count(), lv.triangle_count() * m * m);
    const EdgeTopology topo(lv);
    EXPECT_EQ(t.node_count(), lv.node_count() + topo.edge_count() * (m - 1) +
                                   lv.triangle_count() * (m - 1) * (m - 2) / 2);
    const double a0 = surface_area_mm2(lv), a1 = surface_area_mm2(t);
    EXPECT_NEAR(a1 / a0, 1.0, 1e-12) << "m = " << m;
    EXPECT_NEAR(cavity_volume_ml(t, heart.plane.z_mm), cavity_volume_ml(lv, heart.plane.z_mm), 1e-10);
    // Each tile: parent's tissue, thickness, fibre; a similar copy (area = parent / m^2).
    for (std::size_t p = 0; p < lv.triangle_count(); p += 97)
      for (int k = 0; k < m * m; ++k) {
        const std::size_t c = p * m * m + k;
        EXPECT_EQ(t.tissue[c], lv.tissue[p]);
        EXPECT_EQ(t.thickness_mm[c], lv.thickness_mm[p]);
        EXPECT_EQ(t.fibre[c], lv.fibre[p]);
        EXPECT_NEAR(t.area_mm2(c) * m * m / lv.area_mm2(p), 1.0, 1e-9);
        EXPECT_GT(t.unit_normal(c).dot(lv.unit_normal(p)), 1 - 1e-9);
      }
    // Conforming and oriented; anchors: exactly the base ring, subdivided.
    CheckOptions o;
    o.plane_z_mm = heart.plane.z_mm;
    o.plane_tolerance_mm = 1e-9 * heart.plane.z_mm;
  o.aortic_crown_height_mm = heart.layout.aortic_crown_height_mm;
    o.aortic_crown_height_mm = heart.layout.aortic_crown_height_mm;
    o.degenerate_min_angle_deg = 0.1;
    const auto issues = check_body(t, o);
    EXPECT_TRUE(issues.empty()) << issues.front().message;
    std::size_t anchors0 = 0, anchors1 = 0;
    for (auto r : lv.region) anchors0 += (r & kAnchor) != 0;
    for (auto r : t.region) anchors1 += (r & kAnchor) != 0;
    EXPECT_EQ(anchors1, anchors0 * m);
  }
}

TEST(Tiling, MeetsTheMarkerSpacingOfGridOne) {
  const auto s = config::default_scenario();
  const LeftHeart& heart = default_heart();
  const double target = s.geometry.marker_spacing_fraction * eulerian_spacing_mm(s.fluid);
  EXPECT_NEAR(target, 0.7 * 95.0 / 128.0, 1e-12);  // ~0.52 mm, the seed's grid 1
  const MarkerPlan plan = plan_markers(heart, target);
  for (std::size_t b = 0; b < heart.bodies.size(); ++b) {
    const TriMesh& body = heart.bodies[b];
    const int m = plan.level[b];
    EXPECT_LE(max_edge_mm(body) / m, target) << body.name;
    EXPECT_GT(max_edge_mm(body) / (m - 1), target) << body.name << ": m is the smallest level";
    if (body.triangle_count() > 2000) continue;  // the big ones are covered by the bench
    const TriMesh t = tile(body, m);
    EXPECT_LE(max_edge_mm(t), target * (1 + 1e-12)) << body.name;
    EXPECT_NEAR(surface_area_mm2(t) / surface_area_mm2(body), 1.0, 1e-12) << body.name;
  }
}

TEST(Tiling, LevelOneIsACopy) {
  const TriMesh& cusp = default_heart().body(kAorticCuspBodies[0]);
  const TriMesh t = tile(cusp, 1);
  EXPECT_EQ(t.position_mm, cusp.position_mm);
  EXPECT_EQ(t.tri, cusp.tri);
  EXPECT_THROW(tile(cusp, 0), std::invalid_argument);
}

}  // namespace
}  // namespace systole::geometry

namespace systole::geometry {
namespace {

TEST(Tiling, MarkerHeartAtGridOneIsCleanAndDisjoint) {
  const auto s = config::default_scenario();
  const LeftHeart& heart = default_heart();
  const MarkerPlan plan = plan_markers(heart, s.geometry.marker_spacing_fraction * eulerian_spacing_mm(s.fluid));
  std::vector<TriMesh> tiled;
  for (std::size_t b = 0; b < heart.bodies.size(); ++b) tiled.push_back(tile(heart.bodies[b], plan.level[b]));
  std::vector<const TriMesh*> ptrs;
  for (const auto& t : tiled) ptrs.push_back(&t);
  CheckOptions o;
  o.plane_z_mm = heart.plane.z_mm;
  o.plane_tolerance_mm = 1e-9 * heart.plane.z_mm;
  o.aortic_crown_height_mm = heart.layout.aortic_crown_height_mm;
  o.degenerate_min_angle_deg = 0.1;
  std::size_t triangles = 0;
  for (const auto* t : ptrs) {
    const auto issues = check_body(*t, o);
    EXPECT_TRUE(issues.empty()) << issues.front().message;
    triangles += t->triangle_count();
  }
  const auto x = check_intersections(ptrs);
  EXPECT_TRUE(x.empty()) << x.front().message;
  EXPECT_GT(triangles, 500000u);
  EXPECT_NEAR(cavity_volume_ml(tiled[1], heart.plane.z_mm), 125.0, 1e-9);
  EXPECT_NEAR(cavity_volume_ml(tiled[2], heart.plane.z_mm), 40.0, 1e-9);
}

// The tiling map (the structure mesh <-> the marker mesh of the IB): it reproduces tile()'s
// nodes, interpolates linearly, and its transpose conserves force and moment.
TEST(Tiling, MapReproducesTheTiledNodesAndItsTransposeConservesForceAndMoment) {
  const TriMesh& lv = default_heart().body(kLvBody);
  for (int m : {1, 2, 4}) {
    const TriMesh t = tile(lv, m);
    const TilingMap map = tiling_map(lv, m);
    ASSERT_EQ(map.size(), t.node_count()) << "m = " << m;
    const std::vector<Vec3> x = map.interpolate(lv.position_mm);
    double worst = 0, worst_sum = 0;
    for (std::size_t n = 0; n < x.size(); ++n) {
      worst = std::max(worst, (x[n] - t.position_mm[n]).norm());
      double s = 0;
      for (int k = 0; k < map.count[n]; ++k) {
        EXPECT_GE(map.weight[n][k], 0.0);
        s += map.weight[n][k];
      }
      worst_sum = std::max(worst_sum, std::abs(s - 1));
    }
    // Forces on the tiled nodes spread back: same total force and moment about the origin.
    std::vector<Vec3> f(map.size());
    for (std::size_t n = 0; n < f.size(); ++n)
      f[n] = Vec3(std::sin(0.37 * n), std::cos(0.11 * n), 0.5 - std::sin(0.05 * n));
    const std::vector<Vec3> back = map.spread(f, lv.node_count());
    Vec3 f_tiled = Vec3::Zero(), f_parent = Vec3::Zero(), m_tiled = Vec3::Zero(), m_parent = Vec3::Zero();
    for (std::size_t n = 0; n < f.size(); ++n) {
      f_tiled += f[n];
      m_tiled += x[n].cross(f[n]);
    }
    for (std::size_t n = 0; n < back.size(); ++n) {
      f_parent += back[n];
      m_parent += lv.position_mm[n].cross(back[n]);
    }
    std::printf("  [measured] m = %d: %zu tiled nodes, max |x_map - x_tile| %.2g mm, force %.2g, moment %.2g "
                "(relative)\n", m, map.size(), worst, (f_tiled - f_parent).norm() / f_tiled.norm(),
                (m_tiled - m_parent).norm() / m_tiled.norm());
    EXPECT_LT(worst, 1e-12 * 100);  // positions ~ 100 mm
    EXPECT_LT(worst_sum, 1e-15);
    EXPECT_LT((f_tiled - f_parent).norm(), 1e-12 * f_tiled.norm());
    EXPECT_LT((m_tiled - m_parent).norm(), 1e-12 * m_tiled.norm());
  }
  EXPECT_THROW(tiling_map(lv, 0), std::invalid_argument);
  EXPECT_THROW(tiling_map(lv, 2).spread(std::vector<Vec3>(3), lv.node_count()), std::invalid_argument);
}

}  // namespace
}  // namespace systole::geometry
