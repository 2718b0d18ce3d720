// Each quality check fires on a deliberately broken mesh with a message naming the problem;
// the diagnostics are exact on simple shapes.
#include <gtest/gtest.h>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/quality.h"
#include "solver/geometry/topology.h"

namespace systole::geometry {
namespace {

const LeftHeart& heart() {
  static const LeftHeart h = [] {
    auto s = config::default_scenario();
    s.geometry.target_edge_mm = 3;
    return build_left_heart(s.geometry, s.fluid);
  }();
  return h;
}

CheckOptions options() {
  CheckOptions o;
  o.plane_z_mm = heart().plane.z_mm;
  o.plane_tolerance_mm = 1e-9 * o.plane_z_mm;
  o.degenerate_min_angle_deg = 0.1;
  o.aortic_crown_height_mm = heart().layout.aortic_crown_height_mm;
  return o;
}

// The issues of `mesh` must include one of `check` whose message contains every phrase.
void expect_issue(const TriMesh& mesh, const std::string& check, const std::vector<std::string>& phrases) {
  const auto issues = check_body(mesh, options());
  for (const auto& i : issues) {
    if (i.check != check) continue;
    for (const auto& p : phrases) EXPECT_NE(i.message.find(p), std::string::npos) << i.message;
    return;
  }
  std::string all;
  for (const auto& i : issues) all += "\n  [" + i.check + "] " + i.message;
  ADD_FAILURE() << "no '" << check << "' issue; got:" << all;
}

TEST(Quality, CleanHeartHasNoIssues) {
  for (const auto& b : heart().bodies) EXPECT_TRUE(check_body(b, options()).empty()) << b.name;
  EXPECT_TRUE(check_intersections(heart().body_pointers()).empty());
}

TEST(Quality, NonManifoldEdge) {
  TriMesh lv = heart().body(kLvBody);
  const auto [a, b, c] = lv.tri[100];
  const auto extra = lv.add_node(lv.centroid(100) + 3.0 * lv.unit_normal(100));
  lv.add_triangle(a, b, extra, Tissue::kLvMyocardium, 8, lv.fibre[100]);
  expect_issue(lv, "non_manifold_edge", {"'lv'", "non-manifold", "shared by 3 triangles"});
}

TEST(Quality, InconsistentOrientation) {
  TriMesh lv = heart().body(kLvBody);
  std::swap(lv.tri[200][1], lv.tri[200][2]);
  expect_issue(lv, "inconsistent_orientation", {"'lv'", "inconsistent orientation", "same direction"});
}

TEST(Quality, HoleInAClosedChamber) {
  TriMesh la = heart().body(kLaBody);
  const std::size_t t = la.triangle_count() / 2;
  la.tri.erase(la.tri.begin() + t);
  la.tissue.erase(la.tissue.begin() + t);
  la.thickness_mm.erase(la.thickness_mm.begin() + t);
  la.fibre.erase(la.fibre.begin() + t);
  expect_issue(la, "hole", {"'la'", "hole", "off the valvular plane"});
}

TEST(Quality, DegenerateTriangle) {
  TriMesh lv = heart().body(kLvBody);
  const auto [a, b, c] = lv.tri[300];
  lv.position_mm[c] = 0.5 * (lv.position_mm[a] + lv.position_mm[b]);  // collapses onto an edge
  expect_issue(lv, "degenerate_triangle", {"'lv'", "degenerate", "smallest angle"});
}

TEST(Quality, InvertedTriangle) {
  // Drag an interior node of the (flat) valvular plane across its neighbours: the triangles
  // of its fan that flip face against their neighbours.
  TriMesh plane = heart().body(kValvularPlaneBody);
  const std::int32_t v = static_cast<std::int32_t>(plane.node_count() - 1);  // a lattice node
  std::int32_t neighbour = -1;
  for (const auto& t : plane.tri)
    for (int k = 0; k < 3; ++k)
      if (t[k] == v) neighbour = t[(k + 1) % 3];
  ASSERT_GE(neighbour, 0);
  plane.position_mm[v] += 1.8 * (plane.position_mm[neighbour] - plane.position_mm[v]);
  expect_issue(plane, "inverted_triangle", {"'valvular_plane'", "inverted"});
}

TEST(Quality, InvertedBody) {
  TriMesh lv = heart().body(kLvBody);
  lv.flip_orientation();
  expect_issue(lv, "inverted_body", {"'lv'", "normals point out of the cavity"});
}

TEST(Quality, SelfIntersectionBetweenBodies) {
  TriMesh la = heart().body(kLaBody);
  for (auto& p : la.position_mm) p.z() += 15;  // push the atrium down into the ventricle
  const auto issues = check_intersections({&heart().body(kLvBody), &la});
  ASSERT_FALSE(issues.empty());
  EXPECT_EQ(issues[0].check, "self_intersection");
  EXPECT_NE(issues[0].message.find("bodies 'lv' and 'la' intersect"), std::string::npos) << issues[0].message;
}

TEST(Quality, SelfIntersectionWithinABody) {
  TriMesh aorta = heart().body(kAortaBody);
  // Fold the descending end back through the arch region.
  for (std::size_t i = 0; i < aorta.node_count(); ++i)
    if (aorta.region[i] & kOutflow) aorta.position_mm[i] = heart().plane.aortic_centre_mm - Vec3(0, 0, 10) +
                                                           0.3 * (aorta.position_mm[i] - heart().outflow.end_mm);
  const auto issues = check_intersections({&aorta});
  ASSERT_FALSE(issues.empty());
  EXPECT_NE(issues[0].message.find("body 'aorta' intersects itself"), std::string::npos) << issues[0].message;
}

TEST(Quality, BadTags) {
  {
    TriMesh lv = heart().body(kLvBody);
    lv.region[10] |= 1u << 30;
    expect_issue(lv, "bad_tag", {"unknown region bits", "bit30"});
  }
  {
    TriMesh lv = heart().body(kLvBody);
    for (std::size_t i = 0; i < lv.node_count(); ++i)
      if (lv.region[i] & kAnchor) {
        lv.position_mm[i].z() += 1;  // an anchor lifted off the plane
        break;
      }
    expect_issue(lv, "bad_tag", {"anchor node", "off the valvular plane"});
  }
  {
    TriMesh la = heart().body(kLaBody);
    la.region[la.node_count() / 2] |= kHisBundle;  // His bundle on the atrium
    expect_issue(la, "bad_tag", {"his_bundle", "la_myocardium", "wrong tissue"});
  }
  {
    TriMesh cusp = heart().body(kAorticCuspBodies[1]);
    for (auto& r : cusp.region) r &= ~kAnchor;
    expect_issue(cusp, "bad_tag", {"no node is tagged anchor"});
  }
}

TEST(Quality, BadFibreAndThickness) {
  TriMesh lv = heart().body(kLvBody);
  lv.fibre[5] = lv.unit_normal(5);
  lv.thickness_mm[6] = 0;
  expect_issue(lv, "bad_fibre", {"fibre", "unit tangent"});
  expect_issue(lv, "bad_thickness", {"thickness_mm = 0"});
}

TEST(Quality, ThrowIfIssuesListsEveryProblem) {
  std::vector<QualityIssue> issues{{"hole", "la", "body 'la': 1 hole"}, {"bad_tag", "lv", "body 'lv': x"}};
  try {
    throw_if_issues(issues, "import");
    FAIL();
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("2 problem(s)"), std::string::npos);
    EXPECT_NE(w.find("[hole]"), std::string::npos);
    EXPECT_NE(w.find("[bad_tag]"), std::string::npos);
  }
}

TEST(Quality, ReportOfTheDefaultHeart) {
  const auto s = config::default_scenario();
  const LeftHeart h = build_left_heart(s.geometry, s.fluid);
  for (const auto& b : h.bodies) {
    const auto r = quality_report(b);
    EXPECT_GT(r.min_angle_deg, 5.0) << b.name;
    EXPECT_LT(r.max_aspect_ratio, 12.0) << b.name;
    EXPECT_LE(r.edge_max_mm, 2.0 * s.geometry.target_edge_mm) << b.name;
    EXPECT_NEAR(r.area_mm2, surface_area_mm2(b), 1e-9);
  }
}

// Open unit cube (the top face z = 0 missing, i.e. closed by the "plane" z = 0), normals in.
TriMesh open_box(double side) {
  TriMesh m;
  m.name = "box";
  for (int i = 0; i < 8; ++i) m.add_node(side * Vec3(i & 1, (i >> 1) & 1, (i >> 2) & 1), kAnchor);
  const int quads[5][4] = {{4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    m.add_triangle(q[0], q[1], q[2], Tissue::kLvMyocardium, 1, Vec3::UnitX());
    m.add_triangle(q[0], q[2], q[3], Tissue::kLvMyocardium, 1, Vec3::UnitX());
  }
  if (cavity_volume_ml(m, 0) < 0) m.flip_orientation();
  return m;
}

TEST(Diagnostics, ExactOnABox) {
  const TriMesh box = open_box(10);  // 1 ml
  EXPECT_NEAR(cavity_volume_ml(box, 0), 1.0, 1e-14);
  const Vec3 c = cavity_centroid_mm(box, 0);
  EXPECT_NEAR((c - Vec3(5, 5, 5)).norm(), 0, 1e-12);
  EXPECT_NEAR(surface_area_mm2(box), 500, 1e-12);
  const auto axis = apex_base_axis(box);
  EXPECT_NEAR((axis.base_centre_mm - Vec3(5, 5, 0)).norm(), 0, 1e-12);
  // Shifting the closing plane changes the closed volume accordingly.
  TriMesh shifted = box;
  for (auto& p : shifted.position_mm) p.z() += 3;
  EXPECT_NEAR(cavity_volume_ml(shifted, 3), 1.0, 1e-14);
}

TEST(Diagnostics, LvCavityCentroidOnTheAxis) {
  const LeftHeart& h = heart();
  const Vec3 c = cavity_centroid_mm(h.body(kLvBody), h.plane.z_mm);
  EXPECT_NEAR((c - h.plane.centre_mm).head<2>().norm(), 0, 0.05);
  EXPECT_GT(c.z(), h.plane.z_mm + 20);
  EXPECT_LT(c.z(), h.plane.z_mm + 40);
}

}  // namespace
}  // namespace systole::geometry
