#include "solver/scene/lv_wall_readings.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "solver/diagnostics/kinematics.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/topology.h"

namespace systole::scene {
namespace {

using structure::Vec3;

std::uint64_t edge_key(std::int32_t a, std::int32_t b) {
  const auto lo = static_cast<std::uint64_t>(std::min(a, b)), hi = static_cast<std::uint64_t>(std::max(a, b));
  return (lo << 32) | hi;
}

// cos^2 of every topological edge's angle to the fibre, averaged over its triangles (no fibre: 1/2).
std::unordered_map<std::uint64_t, double> edge_fibre_cos2(const geometry::TriMesh& mesh) {
  const geometry::EdgeTopology topo(mesh);
  std::unordered_map<std::uint64_t, double> cos2;
  cos2.reserve(topo.edge_count());
  for (std::size_t e = 0; e < topo.edge_count(); ++e) {
    const auto [a, b] = topo.edge[e];
    const Vec3 dir = (mesh.position_mm[b] - mesh.position_mm[a]).normalized();
    double sum = 0;
    const int nf = topo.face_count_of(e);
    for (int k = topo.edge_face_offset[e]; k < topo.edge_face_offset[e + 1]; ++k) {
      const Vec3& f = mesh.fibre[static_cast<std::size_t>(topo.edge_face[k])];
      const double fn = f.norm();
      sum += fn > 0 ? std::pow(dir.dot(f) / fn, 2) : 0.5;
    }
    cos2[edge_key(a, b)] = nf > 0 ? sum / nf : 0.5;
  }
  return cos2;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(std::lround(q * static_cast<double>(v.size() - 1)));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

// Area-weighted mean over the triangles with a fibre of the fibre stretch |F f0|, f0 the unit
// fibre projected on the stress-free triangle's plane and F its in-plane deformation gradient.
double mean_fibre_stretch(const geometry::TriMesh& ref, const std::vector<Vec3>& x) {
  double sum = 0, area = 0;
  for (std::size_t t = 0; t < ref.triangle_count(); ++t) {
    const auto& tri = ref.tri[t];
    const Vec3 E1 = ref.position_mm[tri[1]] - ref.position_mm[tri[0]];
    const Vec3 E2 = ref.position_mm[tri[2]] - ref.position_mm[tri[0]];
    const Vec3 n = E1.cross(E2);
    const double a2 = n.norm();
    Vec3 f = ref.fibre[t];
    if (a2 <= 0 || f.norm() == 0) continue;
    f -= f.dot(n / a2) * (n / a2);
    if (f.norm() == 0) continue;
    f.normalize();
    const double g11 = E1.dot(E1), g12 = E1.dot(E2), g22 = E2.dot(E2), det = g11 * g22 - g12 * g12;
    const double r1 = E1.dot(f), r2 = E2.dot(f);
    const double a = (g22 * r1 - g12 * r2) / det, b = (g11 * r2 - g12 * r1) / det;
    const Vec3 Ff = a * (x[tri[1]] - x[tri[0]]) + b * (x[tri[2]] - x[tri[0]]);
    sum += 0.5 * a2 * Ff.norm();
    area += 0.5 * a2;
  }
  return area > 0 ? sum / area : 1;
}

}  // namespace

void add_lv_wall_readings(const structure::ShellModel& lv, const std::string& prefix,
                          std::map<std::string, double>& metrics) {
  const geometry::TriMesh& ref = lv.stress_free_mesh();
  const geometry::ApexBaseAxis axis = geometry::apex_base_axis(ref);
  const diagnostics::WallKinematics w = diagnostics::wall_kinematics(ref, lv.positions_mm(), axis.direction);
  metrics[prefix + "twist_deg"] = w.twist_deg;
  metrics[prefix + "gls_percent"] = 100 * w.longitudinal_strain;
  metrics[prefix + "gcs_percent"] = 100 * w.circumferential_strain;
  metrics[prefix + "fibre_stretch_mean"] = mean_fibre_stretch(ref, lv.positions_mm());

  const auto cos2 = edge_fibre_cos2(ref);
  const std::vector<double> eps = lv.edge_strains();
  std::map<std::string, std::vector<double>> by_direction{{"fibre", {}}, {"cross", {}}, {"oblique", {}}};
  for (std::size_t k = 0; k < eps.size(); ++k) {
    const auto& sp = lv.springs()[k];
    const auto it = cos2.find(edge_key(sp.i, sp.j));
    const double c2 = it == cos2.end() ? 0.5 : it->second;
    by_direction[c2 >= 0.75 ? "fibre" : c2 <= 0.25 ? "cross" : "oblique"].push_back(eps[k]);
  }
  for (const auto& [dir, v] : by_direction) {
    const std::string key = prefix + "edge_strain_" + dir + "_";
    metrics[prefix + "edges_" + dir] = static_cast<double>(v.size());
    if (v.empty()) continue;
    metrics[key + "p05"] = percentile(v, 0.05);
    metrics[key + "p50"] = percentile(v, 0.5);
    metrics[key + "p95"] = percentile(v, 0.95);
    metrics[key + "min"] = *std::min_element(v.begin(), v.end());
    metrics[key + "max"] = *std::max_element(v.begin(), v.end());
  }
}

}  // namespace systole::scene
