#include "solver/scene/fsei/blood.h"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>

#include "solver/core/units.h"
#include "solver/scene/fsei/scales.h"
#include "solver/scene/fsei_scene.h"

namespace systole::scene::fsei {
namespace {

using geometry::Vec3;

// Whether a point lies inside the aorta (ours, for the initial pressure field): within reach_mm
// of an aorta node and on the inner side of the nearest node's inward normal, but not on the
// LV's side of the plane (z >= plane_z) within two orifice radii of the aortic axis (there the
// nearest node is the root's ring, whose normal points at the LV's outflow tract). A bucket
// grid of cell reach_mm.
class AortaInterior {
 public:
  AortaInterior(const geometry::TriMesh& aorta, const geometry::ValvularPlane& plane, double reach_mm)
      : x_(aorta.position_mm),
        n_(geometry::node_normals(aorta)),
        plane_z_mm_(plane.z_mm),
        axis_mm_(plane.aortic_centre_mm),
        outflow_tract_mm_(2 * plane.aortic_radius_mm),
        cell_mm_(reach_mm) {
    lo_ = x_.front();
    for (const Vec3& p : x_) lo_ = lo_.cwiseMin(p);
    for (std::size_t i = 0; i < x_.size(); ++i) buckets_[key(index(x_[i]))].push_back(static_cast<std::int32_t>(i));
  }
  bool inside(const Vec3& p_mm) const {
    if (p_mm.z() >= plane_z_mm_ && (p_mm - axis_mm_).head<2>().norm() < outflow_tract_mm_) return false;
    const std::array<long, 3> k = index(p_mm);
    double best = cell_mm_ * cell_mm_;
    std::int32_t nearest = -1;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int c = -1; c <= 1; ++c) {
          const auto it = buckets_.find(key({k[0] + a, k[1] + b, k[2] + c}));
          if (it == buckets_.end()) continue;
          for (std::int32_t i : it->second) {
            const double d2 = (x_[static_cast<std::size_t>(i)] - p_mm).squaredNorm();
            if (d2 < best) best = d2, nearest = i;
          }
        }
    if (nearest < 0) return false;
    const auto i = static_cast<std::size_t>(nearest);
    return (p_mm - x_[i]).dot(n_[i]) > 0;
  }

 private:
  std::array<long, 3> index(const Vec3& p) const {
    return {static_cast<long>(std::floor((p.x() - lo_.x()) / cell_mm_)),
            static_cast<long>(std::floor((p.y() - lo_.y()) / cell_mm_)),
            static_cast<long>(std::floor((p.z() - lo_.z()) / cell_mm_))};
  }
  static long key(const std::array<long, 3>& k) { return ((k[0] + 1024) * 2048 + (k[1] + 1024)) * 2048 + (k[2] + 1024); }
  std::vector<Vec3> x_, n_;
  double plane_z_mm_;
  Vec3 axis_mm_;
  double outflow_tract_mm_, cell_mm_;
  Vec3 lo_;
  std::unordered_map<long, std::vector<std::int32_t>> buckets_;
};

}  // namespace

std::vector<double> marker_z(const ibm::Markers& markers) {
  std::vector<double> z(markers.size());
  for (std::size_t q = 0; q < markers.size(); ++q) z[q] = markers.markers().position[q].z();
  return z;
}

grid::Slabs fluid_slabs(const config::Scenario& s, const grid::Grid& g, const std::vector<double>& marker_z) {
  return grid::Slabs(g, MPI_COMM_WORLD,
                     s.fsei.slab_split == "balanced" ? slab_plane_weights(g, marker_z) : std::vector<double>{});
}

fluid::FluidParameters fluid_parameters(const config::Scenario& s, const geometry::LeftHeart& heart) {
  fluid::FluidParameters fp;
  fp.reynolds = units::kSeedVelocity_m_s * units::kSeedLength_m / s.fluid.kinematic_viscosity_m2_per_s;
  fp.cfl = s.fluid.cfl;
  fp.cfl_rule = s.fluid.cfl_rule;
  fp.subgrid_model = s.fluid.subgrid_model;
  fp.subgrid_constant = s.fluid.subgrid_constant;
  fp.max_dt = std::min(s.fluid.max_dt_ms, s.fsei.sync_step_ms) / kTimeScaleMs;
  fp.darcy_permeability = s.fluid.darcy_permeability;
  // A stable step below 1e-3 of the largest (velocities 1000x the design's) is a blow-up (ours:
  // a run with 10 forcing passes crawled at 21 ms for ten minutes instead of stopping).
  fp.abort_min_dt = 1e-3 * fp.max_dt;
  // the outflow cylinder's bounding box: its radius reaches r sqrt(1 - a_i^2) along axis i
  const auto& o = heart.outflow;
  const Vec3 a = (o.end_mm - o.start_mm).normalized();
  Vec3 pad;
  for (int i = 0; i < 3; ++i) pad[i] = o.radius_mm * std::sqrt(std::max(0.0, 1 - a[i] * a[i]));
  const Vec3 lo = o.start_mm.cwiseMin(o.end_mm) - pad;
  const Vec3 hi = o.start_mm.cwiseMax(o.end_mm) + pad;
  fp.darcy_regions.push_back(
      {lo.x() / kDmMm, hi.x() / kDmMm, lo.y() / kDmMm, hi.y() / kDmMm, lo.z() / kDmMm, hi.z() / kDmMm});
  return fp;
}

double start_aorta_at_ground_pressure(const config::Scenario& s, const geometry::LeftHeart& heart,
                                      const grid::Grid& g, fluid::FluidSolver& fluid) {
  const config::Fsei& fs = s.fsei;
  if (!(fs.aorta.ground_pressure_mmhg > 0 && fs.aorta.pressure_ramp_ms == 0)) return 0;
  const geometry::TriMesh& aorta = heart.body(geometry::kAortaBody);
  const AortaInterior interior(aorta, heart.plane, 0.75 * s.geometry.aortic_root_diameter_mm);
  const double p0 = fs.aorta.ground_pressure_mmhg * units::kPaPerMmHg /
                    (s.fluid.density_kg_per_m3 * units::kSeedVelocity_m_s * units::kSeedVelocity_m_s);
  long inside_cells = 0;
  fluid.set_pressure([&](double x, double y, double z) {
    if (!interior.inside(Vec3(x, y, z) * kDmMm)) return 0.0;
    ++inside_cells;
    return p0;
  });
  long all = 0;
  MPI_Allreduce(&inside_cells, &all, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  return static_cast<double>(all) * g.dx() * g.dy() * g.dz() * kDmMm * kDmMm * kDmMm * kMlPerMm3;
}

ibm::ForcingParameters forcing_parameters(const config::Fsei::Forcing& forcing) {
  ibm::ForcingParameters f;  // carry_over_factor, carry_over_increment_share, rebuild_tolerance_cells: their defaults
  f.kernel = forcing.kernel == "divergence_free" ? ibm::TransferKernel::divergence_free : ibm::TransferKernel::mls;
  f.iterations = forcing.iterations;
  f.carry_over = forcing.carry_over;
  f.carry_over_exclusion_cells = forcing.carry_over_exclusion_cells;
  f.carry_over_exclusion_rigid = forcing.carry_over_exclusion_plane;  // the plane: the one rigid body
  f.carry_over_exclusion_rigid_cells = forcing.carry_over_exclusion_plane_cells;
  f.carry_over_exclusion_rigid_wall_cells = forcing.carry_over_exclusion_plane_wall_cells;
  return f;
}

}  // namespace systole::scene::fsei
