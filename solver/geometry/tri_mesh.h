#pragma once
// TriMesh: one triangulated tissue surface (one body), stored as a structure of arrays.
//
// Contract
// - Lengths in millimetres, in the seed's frame (MODEL.md §1): z along the LV long axis,
//   pointing down to the apex; the valvular plane is z = const.
// - Per node: position, region tags (a bit set, see Region).
// - Per triangle: three node indices, tissue, thickness_mm, fibre (a unit vector tangent to
//   the triangle).
// - Orientation: the normal of triangle (a, b, c) is (b - a) x (c - a). For chambers and
//   vessels it points into the blood (the cavity / lumen); for leaflets it defines the "+"
//   side, which faces the upper half-space (-z: atrium, aorta) (ours); for the valvular plane
//   it points into the LV (+z) (ours).
// Nothing here allocates per element beyond the arrays; every algorithm over a TriMesh in
// this module is O(n) or O(n log n).
#include <array>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace systole::geometry {

using Vec3 = Eigen::Vector3d;
using Tri = std::array<std::int32_t, 3>;

enum class Tissue : std::uint8_t {
  kValvularPlane = 0,  // rigid fibrous trigone
  kLvMyocardium = 1,
  kLaMyocardium = 2,
  kMitralLeaflet = 3,
  kAorticLeaflet = 4,
  kAorticWall = 5,
  kVeinOstium = 6,  // virtual cap over a pulmonary-vein ostium (open except in atrial systole)
};
inline constexpr int kTissueCount = 7;
std::string_view tissue_name(Tissue t);
// Throws InputError listing the known names.
Tissue tissue_from_name(std::string_view name);

// What closedness the quality checks demand of a body.
enum class BodyKind : std::uint8_t {
  kChamber = 0,  // closed except for boundary loops lying in the valvular plane (LV, LA)
  kVessel = 1,   // a tube: one loop in the valvular plane, other loops open (aorta)
  kLeaflet = 2,  // an open sheet wet on both sides (mitral leaflets, aortic cusps)
  kRigid = 3,    // the valvular plane
};
std::string_view body_kind_name(BodyKind k);
BodyKind body_kind_from_name(std::string_view name);

// Node region tags (bits). A node may carry several.
enum Region : std::uint32_t {
  kRegionNone = 0,
  kAnchor = 1u << 0,              // attached to the rigid valvular plane
  kBachmannBundle = 1u << 1,      // LA stimulus site
  kHisBundle = 1u << 2,           // LV stimulus site (septum near the base)
  kPvOstiumLeftSuperior = 1u << 3,
  kPvOstiumLeftInferior = 1u << 4,
  kPvOstiumRightSuperior = 1u << 5,
  kPvOstiumRightInferior = 1u << 6,
  kLvApex = 1u << 7,              // the apex node
  kLvApexRing = 1u << 8,          // a ring near the apex (twist, strain)
  kLvBaseRing = 1u << 9,          // a ring near the base (twist, strain)
  kOutflow = 1u << 10,            // end of the descending aorta (Darcy afterload region)
  kMitralAnnulus = 1u << 11,
  kAorticAnnulus = 1u << 12,
  kFreeEdge = 1u << 13,           // free edge of a leaflet / cusp
};
inline constexpr std::uint32_t kPvOstiumAny = kPvOstiumLeftSuperior | kPvOstiumLeftInferior |
                                              kPvOstiumRightSuperior | kPvOstiumRightInferior;
inline constexpr int kRegionBitCount = 14;
inline constexpr std::uint32_t kAllRegionBits = (1u << kRegionBitCount) - 1u;
std::string_view region_name(Region bit);
// Throws InputError listing the known names.
Region region_from_name(std::string_view name);
// "anchor|his_bundle" style list of the bits set.
std::string region_list(std::uint32_t bits);

struct TriMesh {
  std::string name;
  BodyKind kind = BodyKind::kChamber;

  // --- nodes ---
  std::vector<Vec3> position_mm;
  std::vector<std::uint32_t> region;

  // --- triangles ---
  std::vector<Tri> tri;
  std::vector<Tissue> tissue;
  std::vector<double> thickness_mm;
  std::vector<Vec3> fibre;

  // --- the stress-free (rest) shape, when it differs from the built one above (ours: the mitral
  // leaflets with geometry.mitral_rest_opening_mm > 0): both empty, or one position per node and
  // one fibre per triangle, on the same triangles ---
  std::vector<Vec3> rest_position_mm;
  std::vector<Vec3> rest_fibre;
  bool has_rest_shape() const { return !rest_position_mm.empty(); }

  std::size_t node_count() const { return position_mm.size(); }
  std::size_t triangle_count() const { return tri.size(); }

  std::int32_t add_node(const Vec3& p, std::uint32_t regions = kRegionNone);
  std::int32_t add_triangle(std::int32_t a, std::int32_t b, std::int32_t c, Tissue t,
                            double thickness, const Vec3& fibre_dir = Vec3::Zero());

  // Unnormalised normal (b - a) x (c - a) (length = 2 * area).
  Vec3 area_vector(std::size_t t) const;
  Vec3 unit_normal(std::size_t t) const;
  double area_mm2(std::size_t t) const;
  Vec3 centroid(std::size_t t) const;

  // Reverses every triangle (swaps two nodes): flips all normals.
  void flip_orientation();
  // Bytes held by the arrays (capacity): the bench's memory figure.
  std::size_t memory_bytes() const;
  // Throws std::logic_error if the arrays disagree in size or an index is out of range.
  void check_arrays() const;
};

// The mesh in its stress-free shape: a copy with position_mm = rest_position_mm and fibre =
// rest_fibre (and no rest arrays); a plain copy when the mesh has no separate rest shape.
TriMesh rest_shape(const TriMesh& mesh);

// Area-weighted node normals (unit; zero for isolated nodes).
std::vector<Vec3> node_normals(const TriMesh& mesh);

// Projects v on the plane of triangle t and normalises; `fallback` if the projection vanishes.
Vec3 tangent_in_triangle(const TriMesh& mesh, std::size_t t, const Vec3& v, const Vec3& fallback);

}  // namespace systole::geometry
