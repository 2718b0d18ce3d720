#pragma once
// Wall kinematics of a deforming chamber mesh (issue #8 and #9 diagnostics): twist about the
// long axis and global longitudinal / circumferential strain. Physics-free: positions in,
// numbers out; the connectivity and the reference (stress-free) positions come from the
// geometry module's TriMesh.
//
// Definitions (ours where marked)
// - Axis: unit vector from base to apex in the REFERENCE configuration (geometry::
//   apex_base_axis), z in the seed's frame. The valvular plane is anchored, so the axis does
//   not move.
// - Ring rotation (deg): the mean over the ring's nodes of the signed angle, about the axis
//   (right-handed), from the node's reference to its current position, both taken relative to
//   the ring's centroid (reference / current) and projected on the plane normal to the axis.
//   Positive = counter-clockwise seen from below (from the apex side, looking towards the
//   base), the seed's convention for systolic twist (MODEL.md §8).
// - Twist (deg) = rotation(apex ring) − rotation(base ring).
// - Fibre-free wall strains (ours): per triangle the in-plane deformation gradient maps the
//   reference edge vectors onto the current ones; the stretch along a reference unit tangent e
//   is |F e|. Longitudinal e: the axis projected on the triangle's reference plane;
//   circumferential e: axis × reference normal, normalised. Triangles whose normal is within 10°
//   of the axis (near the apex, where the directions are undefined) are skipped (ours).
//   Global strain = area-weighted mean of (stretch − 1) over the used triangles (Lagrangian
//   engineering strain; negative = shortening). Echocardiographic GLS/GCS are the same
//   quantities averaged over the wall's mid-layer; here the wall is a surface.
#include <span>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::diagnostics {

using geometry::Vec3;

// Signed rotation (deg) of a set of nodes about `axis`. Throws std::invalid_argument when the
// ring is empty, an index is out of range, or the sizes of the position arrays differ.
double ring_rotation_deg(std::span<const Vec3> reference_mm, std::span<const Vec3> current_mm,
                         std::span<const std::int32_t> ring, const Vec3& axis);

struct WallKinematics {
  double twist_deg = 0;              // apex ring minus base ring
  double apex_rotation_deg = 0;
  double base_rotation_deg = 0;
  double longitudinal_strain = 0;    // global, dimensionless (−0.18 = 18 % shortening)
  double circumferential_strain = 0;
};

// For a chamber mesh whose reference positions are mesh.position_mm and whose nodes carry
// the kLvApexRing / kLvBaseRing tags (the procedural LV does). Only triangles of `tissue` (when
// given) enter the strains. Throws std::invalid_argument when a ring is missing or sizes differ.
WallKinematics wall_kinematics(const geometry::TriMesh& mesh, std::span<const Vec3> current_mm,
                               const Vec3& axis);

// Nodes carrying a region bit.
std::vector<std::int32_t> nodes_with_region(const geometry::TriMesh& mesh, std::uint32_t region_bit);

}  // namespace systole::diagnostics
