#include "solver/geometry/tri_mesh.h"

#include <stdexcept>

#include "solver/core/errors.h"

namespace systole::geometry {

namespace {
constexpr std::array<std::string_view, kTissueCount> kTissueNames{
    "valvular_plane", "lv_myocardium", "la_myocardium", "mitral_leaflet",
    "aortic_leaflet", "aortic_wall",   "vein_ostium"};
constexpr std::array<std::string_view, 4> kKindNames{"chamber", "vessel", "leaflet", "rigid"};
constexpr std::array<std::string_view, kRegionBitCount> kRegionNames{
    "anchor",           "bachmann_bundle",   "his_bundle",        "pv_ostium_left_superior",
    "pv_ostium_left_inferior", "pv_ostium_right_superior", "pv_ostium_right_inferior",
    "lv_apex",          "lv_apex_ring",      "lv_base_ring",      "outflow",
    "mitral_annulus",   "aortic_annulus",    "free_edge"};

template <class Names>
std::string known(const Names& names) {
  std::string s;
  for (auto n : names) s += (s.empty() ? "" : ", ") + std::string(n);
  return s;
}
}  // namespace

std::string_view tissue_name(Tissue t) { return kTissueNames.at(static_cast<int>(t)); }

Tissue tissue_from_name(std::string_view name) {
  for (int i = 0; i < kTissueCount; ++i)
    if (kTissueNames[i] == name) return static_cast<Tissue>(i);
  throw InputError("unknown tissue '" + std::string(name) + "'; known: " + known(kTissueNames));
}

std::string_view body_kind_name(BodyKind k) { return kKindNames.at(static_cast<int>(k)); }

BodyKind body_kind_from_name(std::string_view name) {
  for (int i = 0; i < 4; ++i)
    if (kKindNames[i] == name) return static_cast<BodyKind>(i);
  throw InputError("unknown body kind '" + std::string(name) + "'; known: " + known(kKindNames));
}

std::string_view region_name(Region bit) {
  for (int i = 0; i < kRegionBitCount; ++i)
    if (bit == (1u << i)) return kRegionNames[i];
  return "invalid_region";
}

Region region_from_name(std::string_view name) {
  for (int i = 0; i < kRegionBitCount; ++i)
    if (kRegionNames[i] == name) return static_cast<Region>(1u << i);
  throw InputError("unknown region '" + std::string(name) + "'; known: " + known(kRegionNames));
}

std::string region_list(std::uint32_t bits) {
  std::string s;
  for (int i = 0; i < 32; ++i) {
    if (!(bits & (1u << i))) continue;
    s += s.empty() ? "" : "|";
    s += i < kRegionBitCount ? std::string(kRegionNames[i]) : "bit" + std::to_string(i);
  }
  return s.empty() ? "none" : s;
}

std::int32_t TriMesh::add_node(const Vec3& p, std::uint32_t regions) {
  position_mm.push_back(p);
  region.push_back(regions);
  return static_cast<std::int32_t>(position_mm.size() - 1);
}

std::int32_t TriMesh::add_triangle(std::int32_t a, std::int32_t b, std::int32_t c, Tissue t,
                                   double thickness, const Vec3& fibre_dir) {
  tri.push_back({a, b, c});
  tissue.push_back(t);
  thickness_mm.push_back(thickness);
  fibre.push_back(fibre_dir);
  return static_cast<std::int32_t>(tri.size() - 1);
}

Vec3 TriMesh::area_vector(std::size_t t) const {
  const auto& [a, b, c] = tri[t];
  return (position_mm[b] - position_mm[a]).cross(position_mm[c] - position_mm[a]);
}

Vec3 TriMesh::unit_normal(std::size_t t) const {
  const Vec3 n = area_vector(t);
  const double l = n.norm();
  return l > 0 ? Vec3(n / l) : Vec3::Zero();
}

double TriMesh::area_mm2(std::size_t t) const { return 0.5 * area_vector(t).norm(); }

Vec3 TriMesh::centroid(std::size_t t) const {
  const auto& [a, b, c] = tri[t];
  return (position_mm[a] + position_mm[b] + position_mm[c]) / 3.0;
}

void TriMesh::flip_orientation() {
  for (auto& t : tri) std::swap(t[1], t[2]);
}

std::size_t TriMesh::memory_bytes() const {
  return position_mm.capacity() * sizeof(Vec3) + region.capacity() * sizeof(std::uint32_t) +
         tri.capacity() * sizeof(Tri) + tissue.capacity() * sizeof(Tissue) +
         thickness_mm.capacity() * sizeof(double) + fibre.capacity() * sizeof(Vec3) +
         rest_position_mm.capacity() * sizeof(Vec3) + rest_fibre.capacity() * sizeof(Vec3);
}

void TriMesh::check_arrays() const {
  const std::size_t n = position_mm.size(), m = tri.size();
  if (region.size() != n || tissue.size() != m || thickness_mm.size() != m || fibre.size() != m)
    throw std::logic_error("TriMesh '" + name + "': per-node or per-triangle arrays differ in size");
  if (has_rest_shape() ? (rest_position_mm.size() != n || rest_fibre.size() != m) : !rest_fibre.empty())
    throw std::logic_error("TriMesh '" + name + "': the rest shape's arrays differ in size from the mesh's");
  for (const auto& t : tri)
    for (auto v : t)
      if (v < 0 || static_cast<std::size_t>(v) >= n)
        throw std::logic_error("TriMesh '" + name + "': node index out of range");
}

TriMesh rest_shape(const TriMesh& mesh) {
  mesh.check_arrays();
  TriMesh rest = mesh;
  if (mesh.has_rest_shape()) {
    rest.position_mm = mesh.rest_position_mm;
    rest.fibre = mesh.rest_fibre;
  }
  rest.rest_position_mm.clear();
  rest.rest_fibre.clear();
  return rest;
}

std::vector<Vec3> node_normals(const TriMesh& mesh) {
  std::vector<Vec3> n(mesh.node_count(), Vec3::Zero());
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 a = mesh.area_vector(t);
    for (auto v : mesh.tri[t]) n[v] += a;
  }
  for (auto& v : n) {
    const double l = v.norm();
    if (l > 0) v /= l;
  }
  return n;
}

Vec3 tangent_in_triangle(const TriMesh& mesh, std::size_t t, const Vec3& v, const Vec3& fallback) {
  const Vec3 n = mesh.unit_normal(t);
  Vec3 p = v - v.dot(n) * n;
  const double l = p.norm();
  if (l > 1e-9 * (v.norm() + 1e-300)) return p / l;
  p = fallback - fallback.dot(n) * n;
  const double lf = p.norm();
  return lf > 0 ? Vec3(p / lf) : Vec3::Zero();
}

}  // namespace systole::geometry
