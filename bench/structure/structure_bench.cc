// structure_bench [repeats=3] [--no-tissues] [--no-grid1] : prints the tables of docs/structure.md ("Benchmarks").
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
#include <cstdlib>
#include <fstream>
#include <string>
#include <memory>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/summary.h"
#include "solver/geometry/tiling.h"
#include "solver/structure/contact.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

using namespace systole;

namespace {

struct Throughput {
  double nodes = 0, substeps = 0, cpu = 1e300, wall = 1e300, dt_ms = 0;
};

double load_average() {
  std::ifstream f("/proc/loadavg");
  double l = -1;
  f >> l;
  return l;
}

// The deformable bodies of the heart (optionally tiled to the marker spacing).
std::vector<geometry::TriMesh> heart_meshes(const geometry::LeftHeart& heart, double marker_spacing_mm) {
  std::vector<geometry::TriMesh> meshes;
  for (const auto& b : heart.bodies) {
    if (b.kind == geometry::BodyKind::kRigid) continue;
    meshes.push_back(marker_spacing_mm > 0 ? geometry::tile(b, geometry::tiling_level(b, marker_spacing_mm)) : b);
  }
  return meshes;
}

// Modes: "loop" - bodies one after the other, each body's force loop on `threads` OpenMP
// threads (per-thread buffers); "group" - structure::BodyGroup (lockstep), bodies spread over
// `threads` threads, contact off or on.
enum class Mode { kLoop, kGroup, kGroupContact };

Throughput run_heart(const std::vector<geometry::TriMesh>& meshes, double spacing, const structure::ShellMaterials& mat,
                     double plane_z, int substeps, int threads, Mode mode, int repeats) {
  std::vector<structure::ShellModel> bodies;
  structure::ShellOptions opt;
  opt.cavity_plane_z_mm = plane_z;
  opt.threads = mode == Mode::kLoop ? threads : 1;
  for (const auto& mesh : meshes) {
    bodies.emplace_back(mesh, mat, opt);
    // A small random displacement (1 % of the spacing) so that every force is non-trivial;
    // the cost per substep does not depend on the load.
    std::vector<structure::Vec3> x = mesh.position_mm;
    unsigned seed = 12345;
    auto rnd = [&seed] { seed = seed * 1664525u + 1013904223u; return (seed >> 8) * (1.0 / 16777216.0) - 0.5; };
    for (auto& p : x) p += 0.01 * std::max(spacing, 0.5) * structure::Vec3(rnd(), rnd(), rnd());
    bodies.back().set_state(x, std::vector<structure::Vec3>(x.size(), structure::Vec3::Zero()));
  }
  Throughput t;
  double dt = 1e9;
  for (auto& b : bodies) {
    t.nodes += static_cast<double>(b.node_count());
    dt = std::min(dt, b.stable_step_ms());
  }
  t.dt_ms = dt;
  t.substeps = substeps;
  structure::ContactOptions copt;
  copt.enabled = mode == Mode::kGroupContact;
  std::unique_ptr<structure::BodyGroup> group;
  if (mode != Mode::kLoop) group = std::make_unique<structure::BodyGroup>(bodies, copt, threads);
  // Best of `repeats` (the machine is shared): CPU time of the process and wall time.
  for (int r = 0; r < repeats; ++r) {
    const std::clock_t c0 = std::clock();
    const auto start = std::chrono::steady_clock::now();
    if (group) {
      for (int k = 0; k < substeps; ++k) group->substep(0.5 * dt);
    } else {
      for (int k = 0; k < substeps; ++k)
        for (auto& b : bodies) b.substep(0.5 * dt);
    }
    t.wall = std::min(t.wall, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    t.cpu = std::min(t.cpu, static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const int repeats = argc > 1 ? std::atoi(argv[1]) : 3;
  bool tissue_table = true, grid1 = true;
  for (int k = 2; k < argc; ++k) {
    if (std::string(argv[k]) == "--no-tissues") tissue_table = false;
    if (std::string(argv[k]) == "--no-grid1") grid1 = false;
  }
  const config::Scenario s = config::default_scenario();
  const structure::ShellMaterials mat = structure::materials_from_config(s.tissue);
  const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);

  std::printf("## Throughput (best of %d; node-substeps/s from wall time; load average before each row)\n"
              "| mesh | mode | threads | nodes | substeps | wall s | CPU s | node-substeps/s (wall) | ns per node-substep (wall) | load |\n"
              "|---|---|---|---|---|---|---|---|---|---|\n",
              repeats);
  const double spacing = geometry::eulerian_spacing_mm(s.fluid) * s.geometry.marker_spacing_fraction;
  struct Case {
    const char* name;
    double spacing;
    int substeps;
  };
  char base_name[64], grid_name[64];
  std::snprintf(base_name, sizeof base_name, "default heart (target_edge %.1f mm)", s.geometry.target_edge_mm);
  std::snprintf(grid_name, sizeof grid_name, "grid-1 markers (spacing <= %.2f mm)", spacing);
  const Case cases[] = {{base_name, 0, 400}, {grid_name, spacing, 40}};
  struct Run {
    Mode mode;
    int threads;
    const char* name;
  };
  const Run runs[] = {{Mode::kLoop, 1, "body loop"},
                      {Mode::kLoop, 2, "body loop, force loop split"},
                      {Mode::kGroup, 2, "BodyGroup, bodies over threads"},
                      {Mode::kGroupContact, 1, "BodyGroup + contact"},
                      {Mode::kGroupContact, 2, "BodyGroup + contact, bodies over threads"}};
  for (const Case& c : cases) {
    if (c.spacing > 0 && !grid1) continue;
    const auto meshes = heart_meshes(heart, c.spacing);
    for (const Run& r : runs) {
      const double load = load_average();
      const Throughput t = run_heart(meshes, c.spacing, mat, heart.plane.z_mm, c.substeps, r.threads, r.mode, repeats);
      std::printf("| %s | %s | %d | %.0f | %.0f | %.3f | %.3f | %.3g | %.1f | %.1f |\n", c.name, r.name, r.threads,
                  t.nodes, t.substeps, t.wall, t.cpu, t.nodes * t.substeps / t.wall,
                  1e9 * t.wall / (t.nodes * t.substeps), load);
      std::fflush(stdout);
    }
  }
  if (!tissue_table) return 0;

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
