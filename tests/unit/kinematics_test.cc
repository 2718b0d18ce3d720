// solver/diagnostics/kinematics: twist and global strains under motions whose answer is known.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "solver/config/scenario.h"
#include "solver/diagnostics/kinematics.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"

namespace systole::diagnostics {
namespace {

using geometry::Vec3;
constexpr double kPi = std::numbers::pi;

const geometry::TriMesh& lv() {
  static const geometry::LeftHeart heart = [] {
    config::Scenario s = config::default_scenario();
    s.geometry.target_edge_mm = 4;  // coarse: the identities below hold at any resolution
    return geometry::build_left_heart(s.geometry, s.fluid);
  }();
  return heart.body(geometry::kLvBody);
}

Vec3 rotate_about(const Vec3& p, const Vec3& origin, const Vec3& axis, double angle_rad) {
  return origin + Eigen::AngleAxisd(angle_rad, axis.normalized()) * (p - origin);
}

TEST(Kinematics, PositiveRotationAboutTheBaseToApexAxisIsCounterClockwiseSeenFromBelow) {
  // z points to the apex (down). Seen from below, i.e. from +z looking back along −z, the x–y
  // plane appears with x to the right and y up, so x → y is counter-clockwise.
  const std::vector<Vec3> ref{{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}};
  std::vector<Vec3> cur;
  for (const Vec3& p : ref) cur.push_back(rotate_about(p, Vec3::Zero(), Vec3::UnitZ(), 0.1));
  const std::vector<std::int32_t> ring{0, 1, 2, 3};
  EXPECT_NEAR(ring_rotation_deg(ref, cur, ring, Vec3::UnitZ()), 0.1 * 180 / kPi, 1e-12);
  EXPECT_NEAR(ring_rotation_deg(ref, cur, ring, -Vec3::UnitZ()), -0.1 * 180 / kPi, 1e-12);
}

TEST(Kinematics, RigidRotationHasNoTwistAndNoStrain) {
  const auto& mesh = lv();
  const auto axis = geometry::apex_base_axis(mesh);
  std::vector<Vec3> cur;
  for (const Vec3& p : mesh.position_mm) cur.push_back(rotate_about(p, axis.base_centre_mm, axis.direction, 0.3));
  const WallKinematics k = wall_kinematics(mesh, cur, axis.direction);
  EXPECT_NEAR(k.apex_rotation_deg, 0.3 * 180 / kPi, 1e-9);
  EXPECT_NEAR(k.base_rotation_deg, 0.3 * 180 / kPi, 1e-9);
  EXPECT_NEAR(k.twist_deg, 0, 1e-9);
  EXPECT_NEAR(k.longitudinal_strain, 0, 1e-12);
  EXPECT_NEAR(k.circumferential_strain, 0, 1e-12);
}

TEST(Kinematics, TorsionLinearAlongTheAxisGivesTheTwistBetweenTheRings) {
  const auto& mesh = lv();
  const auto axis = geometry::apex_base_axis(mesh);
  const double rate_rad_per_mm = 0.004;  // 0.23°/mm, ≈ 17° over the 75 mm LV
  auto height = [&](const Vec3& p) { return (p - axis.base_centre_mm).dot(axis.direction); };
  std::vector<Vec3> cur;
  for (const Vec3& p : mesh.position_mm)
    cur.push_back(rotate_about(p, axis.base_centre_mm, axis.direction, rate_rad_per_mm * height(p)));
  // Expected: each ring node turns by rate·height; the ring's rotation is their mean (exact
  // when the ring's centroid is on the axis, which the symmetric procedural rings satisfy).
  auto mean_height = [&](std::uint32_t bit) {
    double s = 0;
    const auto nodes = nodes_with_region(mesh, bit);
    for (auto i : nodes) s += height(mesh.position_mm[static_cast<std::size_t>(i)]);
    return s / static_cast<double>(nodes.size());
  };
  const double expected_deg =
      rate_rad_per_mm * (mean_height(geometry::kLvApexRing) - mean_height(geometry::kLvBaseRing)) * 180 / kPi;
  const WallKinematics k = wall_kinematics(mesh, cur, axis.direction);
  EXPECT_GT(expected_deg, 5);
  EXPECT_NEAR(k.twist_deg, expected_deg, 1e-6 * expected_deg);
}

TEST(Kinematics, UniformScalingGivesEqualStrainsAndAxialStretchNoCircumferentialStrain) {
  const auto& mesh = lv();
  const auto axis = geometry::apex_base_axis(mesh);
  std::vector<Vec3> scaled, stretched;
  for (const Vec3& p : mesh.position_mm) {
    scaled.push_back(axis.base_centre_mm + 0.85 * (p - axis.base_centre_mm));
    const Vec3 d = p - axis.base_centre_mm;
    stretched.push_back(p + 0.1 * d.dot(axis.direction) * axis.direction);  // axial stretch 1.1
  }
  const WallKinematics s = wall_kinematics(mesh, scaled, axis.direction);
  EXPECT_NEAR(s.longitudinal_strain, -0.15, 1e-12);
  EXPECT_NEAR(s.circumferential_strain, -0.15, 1e-12);
  EXPECT_NEAR(s.twist_deg, 0, 1e-9);
  const WallKinematics a = wall_kinematics(mesh, stretched, axis.direction);
  EXPECT_NEAR(a.circumferential_strain, 0, 1e-12);
  EXPECT_GT(a.longitudinal_strain, 0.01);
  EXPECT_LT(a.longitudinal_strain, 0.1);
}

TEST(Kinematics, BadInputIsRejected) {
  const auto& mesh = lv();
  std::vector<Vec3> too_few(mesh.position_mm.begin(), mesh.position_mm.end() - 1);
  EXPECT_THROW(wall_kinematics(mesh, too_few, Vec3::UnitZ()), std::invalid_argument);
  geometry::TriMesh untagged = mesh;
  for (auto& r : untagged.region) r &= ~geometry::kLvApexRing;
  EXPECT_THROW(wall_kinematics(untagged, mesh.position_mm, Vec3::UnitZ()), std::invalid_argument);
  EXPECT_THROW(ring_rotation_deg(mesh.position_mm, mesh.position_mm, std::vector<std::int32_t>{}, Vec3::UnitZ()),
               std::invalid_argument);
}

}  // namespace
}  // namespace systole::diagnostics
