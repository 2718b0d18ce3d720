#include "solver/scene/fsei/probes.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>

#include "solver/core/errors.h"
#include "solver/scene/fsei/scales.h"

namespace systole::scene::fsei {

using geometry::Vec3;

std::vector<Probe> chamber_probes(const config::Scenario& s, const geometry::LeftHeart& heart) {
  const Vec3 lv_c = heart.plane.centre_mm + 0.4 * s.geometry.lv_long_axis_mm * heart.lv_axis_direction;
  const Vec3 ao_c = heart.plane.aortic_centre_mm - 8.0 * heart.lv_axis_direction;
  Vec3 la_c = Vec3::Zero();
  for (const Vec3& p : heart.body(geometry::kLaBody).position_mm) la_c += p;
  la_c /= static_cast<double>(heart.body(geometry::kLaBody).node_count());
  const double r = s.fsei.probe_radius_mm + 1;
  const Vec3 ref(r, r, 0.5 * s.fluid.box_z_mm);
  const Vec3 down = (heart.outflow.end_mm - heart.outflow.start_mm).normalized();
  const Vec3 desc_c = heart.outflow.start_mm - heart.outflow.radius_mm * down;
  return {{"lv", lv_c}, {"la", la_c}, {"aortic_root", ao_c}, {"outer", ref}, {"descending_aorta", desc_c}};
}

// Mean pressure (nondimensional) over the cells whose centres lie within radius of each probe.
// Collective. Throws InputError when a probe holds no cell centre.
std::vector<double> probe_pressures(const fluid::FluidSolver& fluid, const std::vector<Probe>& probes,
                                    double radius_mm) {
  const grid::Slabs& slabs = fluid.slabs();
  const grid::Grid& g = slabs.grid();
  const grid::CellField& p = fluid.pressure();
  const std::size_t n = probes.size();
  std::vector<double> sum(2 * n, 0.0);
  const double r = radius_mm / kDmMm;
  for (std::size_t q = 0; q < n; ++q) {
    const Vec3 c = probes[q].centre_mm / kDmMm;
    const int k0 = std::max(slabs.k_begin(), static_cast<int>(std::floor((c.z() - r) / g.dz())));
    const int k1 = std::min(slabs.k_begin() + slabs.k_count() - 1, static_cast<int>(std::ceil((c.z() + r) / g.dz())));
    const int j0 = std::max(0, static_cast<int>(std::floor((c.y() - r) / g.dy())));
    const int j1 = std::min(g.ny() - 1, static_cast<int>(std::ceil((c.y() + r) / g.dy())));
    const int i0 = std::max(0, static_cast<int>(std::floor((c.x() - r) / g.dx())));
    const int i1 = std::min(g.nx() - 1, static_cast<int>(std::ceil((c.x() + r) / g.dx())));
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const Vec3 x(g.x(grid::Location::cell, i), g.y(grid::Location::cell, j), g.z(grid::Location::cell, k));
          if ((x - c).norm() > r) continue;
          sum[2 * q] += p(i, j, k - slabs.k_begin());
          sum[2 * q + 1] += 1;
        }
  }
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), static_cast<int>(sum.size()), MPI_DOUBLE, MPI_SUM, slabs.comm());
  std::vector<double> mean(n);
  for (std::size_t q = 0; q < n; ++q) {
    if (sum[2 * q + 1] == 0)
      throw InputError("fsei.probe_radius_mm = " + std::to_string(radius_mm) + " mm: the " + probes[q].name +
                       " probe holds no cell centre; allowed: at least half the grid spacing");
    mean[q] = sum[2 * q] / sum[2 * q + 1];
  }
  return mean;
}

// The z-velocity summed over the z-faces of the disk of `radius_mm` around `centre_mm` on the
// z-face plane nearest to its z, and the number of those faces (nondimensional). Collective.
namespace {
std::array<double, 2> disk_sum_w(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const grid::Slabs& slabs = fluid.slabs();
  const grid::Grid& g = slabs.grid();
  const Vec3 c = centre_mm / kDmMm;
  const double r = radius_mm / kDmMm;
  const int k = static_cast<int>(std::lround(c.z() / g.dz()));
  std::array<double, 2> sum{0, 0};
  if (k >= slabs.k_begin() && k < slabs.k_begin() + slabs.k_count()) {
    const grid::ZFaceField& w = fluid.velocity().w;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        const double dx = g.x(grid::Location::z_face, i) - c.x(), dy = g.y(grid::Location::z_face, j) - c.y();
        if (dx * dx + dy * dy <= r * r) sum[0] += w(i, j, k - slabs.k_begin()), sum[1] += 1;
      }
  }
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), 2, MPI_DOUBLE, MPI_SUM, slabs.comm());
  return sum;
}

}  // namespace

// Volume flux (nondimensional, + along +z) through that disk. Collective.
double disk_flux(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const grid::Grid& g = fluid.slabs().grid();
  return disk_sum_w(fluid, centre_mm, radius_mm)[0] * g.dx() * g.dy();
}

// Mean z-velocity (nondimensional) over that disk: a Doppler-like sample volume (ours: one face
// layer). Collective; 0 when the disk holds no face.
double disk_mean_w(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const std::array<double, 2> sum = disk_sum_w(fluid, centre_mm, radius_mm);
  return sum[1] > 0 ? sum[0] / sum[1] : 0.0;
}

}  // namespace systole::scene::fsei
