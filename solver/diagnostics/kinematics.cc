#include "solver/diagnostics/kinematics.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace systole::diagnostics {
namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

Vec3 centroid(std::span<const Vec3> p, std::span<const std::int32_t> ring) {
  Vec3 c = Vec3::Zero();
  for (std::int32_t i : ring) c += p[static_cast<std::size_t>(i)];
  return c / static_cast<double>(ring.size());
}

}  // namespace

std::vector<std::int32_t> nodes_with_region(const geometry::TriMesh& mesh, std::uint32_t region_bit) {
  std::vector<std::int32_t> nodes;
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if (mesh.region[i] & region_bit) nodes.push_back(static_cast<std::int32_t>(i));
  return nodes;
}

double ring_rotation_deg(std::span<const Vec3> reference_mm, std::span<const Vec3> current_mm,
                         std::span<const std::int32_t> ring, const Vec3& axis_in) {
  if (ring.empty()) throw std::invalid_argument("ring_rotation_deg: empty ring");
  if (reference_mm.size() != current_mm.size())
    throw std::invalid_argument("ring_rotation_deg: " + std::to_string(reference_mm.size()) +
                                " reference positions but " + std::to_string(current_mm.size()) + " current ones");
  for (std::int32_t i : ring)
    if (i < 0 || static_cast<std::size_t>(i) >= reference_mm.size())
      throw std::invalid_argument("ring_rotation_deg: node index " + std::to_string(i) + " out of range");
  const Vec3 axis = axis_in.normalized();
  const Vec3 c0 = centroid(reference_mm, ring), c1 = centroid(current_mm, ring);
  double sum = 0;
  for (std::int32_t i : ring) {
    Vec3 a = reference_mm[static_cast<std::size_t>(i)] - c0;
    Vec3 b = current_mm[static_cast<std::size_t>(i)] - c1;
    a -= a.dot(axis) * axis;
    b -= b.dot(axis) * axis;
    // atan2(|a×b|·sign, a·b): the signed angle about the axis, in (−180°, 180°].
    sum += std::atan2(axis.dot(a.cross(b)), a.dot(b));
  }
  return kDeg * sum / static_cast<double>(ring.size());
}

WallKinematics wall_kinematics(const geometry::TriMesh& mesh, std::span<const Vec3> current_mm,
                               const Vec3& axis_in) {
  if (current_mm.size() != mesh.node_count())
    throw std::invalid_argument("wall_kinematics: mesh '" + mesh.name + "' has " + std::to_string(mesh.node_count()) +
                                " nodes but " + std::to_string(current_mm.size()) + " current positions were given");
  const auto apex = nodes_with_region(mesh, geometry::kLvApexRing);
  const auto base = nodes_with_region(mesh, geometry::kLvBaseRing);
  if (apex.empty() || base.empty())
    throw std::invalid_argument("wall_kinematics: mesh '" + mesh.name + "' has no " +
                                (apex.empty() ? "lv_apex_ring" : "lv_base_ring") + " nodes");
  const Vec3 axis = axis_in.normalized();
  WallKinematics k;
  const std::span<const Vec3> reference(mesh.position_mm);
  k.apex_rotation_deg = ring_rotation_deg(reference, current_mm, apex, axis);
  k.base_rotation_deg = ring_rotation_deg(reference, current_mm, base, axis);
  k.twist_deg = k.apex_rotation_deg - k.base_rotation_deg;

  const double skip_cos = std::cos(10.0 / kDeg);
  double area_l = 0, area_c = 0, sum_l = 0, sum_c = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto& tri = mesh.tri[t];
    const Vec3& A = mesh.position_mm[static_cast<std::size_t>(tri[0])];
    const Vec3 D1 = mesh.position_mm[static_cast<std::size_t>(tri[1])] - A;
    const Vec3 D2 = mesh.position_mm[static_cast<std::size_t>(tri[2])] - A;
    const Vec3 d1 = current_mm[static_cast<std::size_t>(tri[1])] - current_mm[static_cast<std::size_t>(tri[0])];
    const Vec3 d2 = current_mm[static_cast<std::size_t>(tri[2])] - current_mm[static_cast<std::size_t>(tri[0])];
    const Vec3 cross = D1.cross(D2);
    const double area = 0.5 * cross.norm();
    if (area <= 0) continue;
    const Vec3 n = cross.normalized();
    if (std::abs(n.dot(axis)) > skip_cos) continue;
    const Vec3 e_l = (axis - axis.dot(n) * n).normalized();
    const Vec3 e_c = axis.cross(n).normalized();
    // e = α D1 + β D2 (e in the reference plane): solve the 2×2 Gram system.
    const double g11 = D1.dot(D1), g12 = D1.dot(D2), g22 = D2.dot(D2), det = g11 * g22 - g12 * g12;
    auto stretch = [&](const Vec3& e) {
      const double r1 = e.dot(D1), r2 = e.dot(D2);
      const double alpha = (g22 * r1 - g12 * r2) / det, beta = (g11 * r2 - g12 * r1) / det;
      return (alpha * d1 + beta * d2).norm();
    };
    sum_l += area * (stretch(e_l) - 1);
    sum_c += area * (stretch(e_c) - 1);
    area_l += area;
    area_c += area;
  }
  if (area_l <= 0) throw std::invalid_argument("wall_kinematics: mesh '" + mesh.name + "' has no usable triangle");
  k.longitudinal_strain = sum_l / area_l;
  k.circumferential_strain = sum_c / area_c;
  return k;
}

}  // namespace systole::diagnostics
