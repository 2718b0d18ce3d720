#include "solver/geometry/diagnostics.h"

#include <stdexcept>

#include "solver/geometry/topology.h"

namespace systole::geometry {

double cavity_volume_ml(const TriMesh& mesh, double plane_z_mm) {
  double v = 0;  // mm^3
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const Vec3 n2a = mesh.area_vector(t);  // 2 A n
    v -= (mesh.centroid(t).z() - plane_z_mm) * 0.5 * n2a.z();
  }
  return v * 1e-3;
}

Vec3 cavity_centroid_mm(const TriMesh& mesh, double plane_z_mm) {
  // Fields vanishing on z = z_p: F_x = (z - z_p) x e_z (div = x), F_y likewise,
  // F_z = ((z - z_p)^2 / 2 + z_p (z - z_p)) e_z (div = z). Integrands are quadratic on each
  // triangle: the three edge midpoints integrate them exactly.
  Vec3 moment = Vec3::Zero();
  double volume = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto& [ia, ib, ic] = mesh.tri[t];
    const Vec3 &a = mesh.position_mm[ia], &b = mesh.position_mm[ib], &c = mesh.position_mm[ic];
    const double nz_area = 0.5 * mesh.area_vector(t).z();  // n_z * A
    const Vec3 mids[3] = {0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)};
    for (const Vec3& q : mids) {
      const double dz = q.z() - plane_z_mm;
      const double w = -nz_area / 3.0;
      moment.x() += w * dz * q.x();
      moment.y() += w * dz * q.y();
      moment.z() += w * (0.5 * dz * dz + plane_z_mm * dz);
      volume += w * dz;
    }
  }
  return volume != 0 ? Vec3(moment / volume) : Vec3::Zero();
}

double surface_area_mm2(const TriMesh& mesh, std::optional<Tissue> tissue) {
  double a = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    if (!tissue || mesh.tissue[t] == *tissue) a += mesh.area_mm2(t);
  return a;
}

Vec3 surface_centroid_mm(const TriMesh& mesh) {
  Vec3 s = Vec3::Zero();
  double a = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const double w = mesh.area_mm2(t);
    s += w * mesh.centroid(t);
    a += w;
  }
  return a > 0 ? Vec3(s / a) : Vec3::Zero();
}

ApexBaseAxis apex_base_axis(const TriMesh& mesh) {
  const EdgeTopology topo(mesh);
  const auto loops = boundary_loops(mesh, topo);
  if (loops.empty())
    throw std::invalid_argument("apex_base_axis: mesh '" + mesh.name + "' has no open base");
  // Area centroid of the largest boundary polygon (fan from its vertex mean).
  const auto* base = &loops[0];
  for (const auto& l : loops)
    if (l.size() > base->size()) base = &l;
  Vec3 mean = Vec3::Zero();
  for (auto v : *base) mean += mesh.position_mm[v];
  mean /= static_cast<double>(base->size());
  Vec3 acc = Vec3::Zero();
  double area = 0;
  for (std::size_t i = 0; i < base->size(); ++i) {
    const Vec3& p = mesh.position_mm[(*base)[i]];
    const Vec3& q = mesh.position_mm[(*base)[(i + 1) % base->size()]];
    const double w = (p - mean).cross(q - mean).norm();
    acc += w * (mean + p + q) / 3.0;
    area += w;
  }
  ApexBaseAxis axis{};
  axis.base_centre_mm = area > 0 ? Vec3(acc / area) : mean;
  std::int64_t apex = -1;
  double far = -1;
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    if (mesh.region[i] & kLvApex) {
      apex = static_cast<std::int64_t>(i);
      break;
    }
    const double d = (mesh.position_mm[i] - axis.base_centre_mm).norm();
    if (d > far) {
      far = d;
      apex = static_cast<std::int64_t>(i);
    }
  }
  axis.apex_mm = mesh.position_mm[apex];
  const Vec3 d = axis.apex_mm - axis.base_centre_mm;
  axis.length_mm = d.norm();
  axis.direction = axis.length_mm > 0 ? Vec3(d / axis.length_mm) : Vec3::UnitZ();
  return axis;
}

}  // namespace systole::geometry
