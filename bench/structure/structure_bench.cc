// structure_bench [--threads-note] : prints the tables of docs/structure.md ("Benchmarks").
// 1. Node-substeps per second of ShellModel::substep on every deformable body of the default
//    left heart (base mesh, geometry.target_edge_mm) and of the heart tiled to the seed's
//    grid-1 marker spacing (0.7 x 95/128 mm), at a small cavity pressure, fixed substep.
// 2. The reported stable step of each tissue (seed c, alpha, the default thicknesses) on a
//    flat equilateral sheet with the heart's edge length, at rest and stretched by 20 %
//    (eps = (l - l0)/l = 0.2 on every edge), fibre along one edge family.
#include <algorithm>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/summary.h"
#include "solver/geometry/tiling.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

using namespace systole;

namespace {

struct Throughput {
  double nodes = 0, substeps = 0, seconds = 0, wall = 0, dt_ms = 0;
};

Throughput run_heart(const geometry::LeftHeart& heart, double marker_spacing_mm, const structure::ShellMaterials& mat,
                     int substeps, int threads) {
  std::vector<std::unique_ptr<structure::ShellModel>> bodies;
  structure::ShellOptions opt;
  opt.cavity_plane_z_mm = heart.plane.z_mm;
  opt.threads = threads;
  for (const auto& b : heart.bodies) {
    if (b.kind == geometry::BodyKind::kRigid) continue;
    geometry::TriMesh mesh = b;
    if (marker_spacing_mm > 0) mesh = geometry::tile(b, geometry::tiling_level(b, marker_spacing_mm));
    bodies.push_back(std::make_unique<structure::ShellModel>(mesh, mat, opt));
    // A small random displacement (1 % of the spacing) so that every force is non-trivial;
    // the cost per substep does not depend on the load.
    std::vector<structure::Vec3> x = mesh.position_mm;
    unsigned seed = 12345;
    auto rnd = [&seed] { seed = seed * 1664525u + 1013904223u; return (seed >> 8) * (1.0 / 16777216.0) - 0.5; };
    for (auto& p : x) p += 0.01 * std::max(marker_spacing_mm, 0.5) * structure::Vec3(rnd(), rnd(), rnd());
    bodies.back()->set_state(x, std::vector<structure::Vec3>(x.size(), structure::Vec3::Zero()));
  }
  Throughput t;
  double dt = 1e9;
  for (auto& b : bodies) {
    t.nodes += static_cast<double>(b->node_count());
    dt = std::min(dt, b->stable_step_ms());
  }
  t.dt_ms = dt;
  // CPU time of this process (the machine is shared: wall time is also printed).
  const std::clock_t c0 = std::clock();
  const auto start = std::chrono::steady_clock::now();
  for (int k = 0; k < substeps; ++k)
    for (auto& b : bodies) b->substep(0.5 * dt);
  t.wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  t.seconds = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
  t.substeps = substeps;
  return t;
}

}  // namespace

int main() {
  const config::Scenario s = config::default_scenario();
  const structure::ShellMaterials mat = structure::materials_from_config(s.tissue);
  const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);

  std::printf("## Throughput (CPU time; node-substeps/s from CPU time, and from wall time)\n| mesh | nodes | substeps | CPU s (wall s) | node-substeps/s | ns per node-substep |\n|---|---|---|---|---|---|\n");
  const double spacing = geometry::eulerian_spacing_mm(s.fluid) * s.geometry.marker_spacing_fraction;
  for (int threads : {1, 2}) {
    {
      const Throughput t = run_heart(heart, 0, mat, 400, threads);
      std::printf("| default heart (target_edge %.1f mm), %d thread(s) | %.0f | %.0f | %.3f (%.3f) | %.3g (wall %.3g) | %.1f |\n",
                  s.geometry.target_edge_mm, threads, t.nodes, t.substeps, t.seconds, t.wall,
                  t.nodes * t.substeps / t.seconds, t.nodes * t.substeps / t.wall,
                  1e9 * t.seconds / (t.nodes * t.substeps));
    }
    {
      const Throughput t = run_heart(heart, spacing, mat, 40, threads);
      std::printf("| grid-1 markers (spacing <= %.2f mm), %d thread(s) | %.0f | %.0f | %.3f (%.3f) | %.3g (wall %.3g) | %.1f |\n",
                  spacing, threads, t.nodes, t.substeps, t.seconds, t.wall, t.nodes * t.substeps / t.seconds,
                  t.nodes * t.substeps / t.wall, 1e9 * t.seconds / (t.nodes * t.substeps));
    }
  }

  std::printf("\n## Reported stable step per tissue (flat sheet, fibre along an edge family)\n"
              "| tissue | c (Pa) | thickness (mm) | edge (mm) | dt at rest (ms) | dt at eps = 0.2 (ms) | ratio |\n|---|---|---|---|---|---|---|\n");
  struct T {
    const char* name;
    geometry::Tissue tissue;
    double c_pa, s_mm;
  };
  const config::Geometry& g = s.geometry;
  const T tissues[] = {{"LV", geometry::Tissue::kLvMyocardium, s.tissue.lv.fung_c_pa, g.lv_wall_mm},
                       {"LA", geometry::Tissue::kLaMyocardium, s.tissue.la.fung_c_pa, g.la_wall_mm},
                       {"mitral leaflets", geometry::Tissue::kMitralLeaflet, s.tissue.mitral_leaflets.fung_c_pa,
                        g.mitral_leaflet_thickness_mm},
                       {"aortic cusps", geometry::Tissue::kAorticLeaflet, s.tissue.aortic_leaflets.fung_c_pa,
                        g.aortic_leaflet_thickness_mm},
                       {"aorta", geometry::Tissue::kAorticWall, s.tissue.aorta.fung_c_pa, g.aorta_wall_mm}};
  for (double edge : {s.geometry.target_edge_mm, 0.5}) {
    for (const T& t : tissues) {
      auto mesh = structure::flat_sheet(12, 12, edge, t.s_mm, t.tissue, {1, 0, 0});
      structure::ShellModel body(mesh, mat, structure::ShellOptions{});
      const double rest = body.stable_step_ms();
      std::vector<structure::Vec3> x = mesh.position_mm;
      for (auto& p : x) p /= (1 - 0.2);
      body.set_state(x, std::vector<structure::Vec3>(x.size(), structure::Vec3::Zero()));
      const double strained = body.stable_step_ms();
      std::printf("| %s | %.1f | %.1f | %.2f | %.4g | %.4g | %.1f |\n", t.name, t.c_pa, t.s_mm, edge, rest, strained,
                  rest / strained);
    }
  }
  return 0;
}
