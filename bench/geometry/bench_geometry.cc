// Geometry benchmarks: build the default heart (base mesh, target_edge_mm = 2, with all its
// checks) and tile it to the seed's grid-1 marker spacing (0.7 x 95/128 mm ~ 0.52 mm).
// Counters: base and marker node/triangle counts and the marker meshes' memory.
// Run: build/bench/bench_geometry   (results go to docs/benchmarks.md and docs/geometry.md)
#include <benchmark/benchmark.h>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/quality.h"
#include "solver/geometry/summary.h"
#include "solver/geometry/tiling.h"

using namespace systole;
using namespace systole::geometry;

static void BM_BuildDefaultHeart(benchmark::State& state) {
  const auto s = config::default_scenario();
  std::size_t nodes = 0, tris = 0;
  for (auto _ : state) {
    const LeftHeart heart = build_left_heart(s.geometry, s.fluid);
    nodes = tris = 0;
    for (const auto& b : heart.bodies) {
      nodes += b.node_count();
      tris += b.triangle_count();
    }
    benchmark::DoNotOptimize(heart.bodies.data());
  }
  state.counters["nodes"] = static_cast<double>(nodes);
  state.counters["triangles"] = static_cast<double>(tris);
}
BENCHMARK(BM_BuildDefaultHeart)->Unit(benchmark::kMillisecond);

static void BM_TileDefaultHeartToGrid1(benchmark::State& state) {
  const auto s = config::default_scenario();
  const LeftHeart heart = build_left_heart(s.geometry, s.fluid);
  const double target = s.geometry.marker_spacing_fraction * eulerian_spacing_mm(s.fluid);
  const MarkerPlan plan = plan_markers(heart, target);
  std::size_t nodes = 0, tris = 0, bytes = 0;
  for (auto _ : state) {
    nodes = tris = bytes = 0;
    for (std::size_t b = 0; b < heart.bodies.size(); ++b) {
      const TriMesh t = tile(heart.bodies[b], plan.level[b]);
      nodes += t.node_count();
      tris += t.triangle_count();
      bytes += t.memory_bytes();
      benchmark::DoNotOptimize(t.position_mm.data());
    }
  }
  state.counters["marker_spacing_mm"] = target;
  state.counters["marker_nodes"] = static_cast<double>(nodes);
  state.counters["marker_triangles"] = static_cast<double>(tris);
  state.counters["marker_MB"] = static_cast<double>(bytes) / 1e6;
}
BENCHMARK(BM_TileDefaultHeartToGrid1)->Unit(benchmark::kMillisecond);

// Build + tile end to end, plus the quality and intersection checks on the marker meshes.
static void BM_BuildTileAndCheckMarkers(benchmark::State& state) {
  const auto s = config::default_scenario();
  const double target = s.geometry.marker_spacing_fraction * eulerian_spacing_mm(s.fluid);
  for (auto _ : state) {
    const LeftHeart heart = build_left_heart(s.geometry, s.fluid);
    const MarkerPlan plan = plan_markers(heart, target);
    std::vector<TriMesh> tiled;
    for (std::size_t b = 0; b < heart.bodies.size(); ++b) tiled.push_back(tile(heart.bodies[b], plan.level[b]));
    std::vector<const TriMesh*> ptrs;
    for (const auto& t : tiled) ptrs.push_back(&t);
    CheckOptions o;
    o.plane_z_mm = heart.plane.z_mm;
    o.plane_tolerance_mm = 1e-9 * heart.plane.z_mm;
    o.aortic_crown_height_mm = heart.layout.aortic_crown_height_mm;
    o.degenerate_min_angle_deg = 0.1;
    std::size_t issues = 0;
    for (const auto* t : ptrs) issues += check_body(*t, o).size();
    issues += check_intersections(ptrs).size();
    if (issues) state.SkipWithError("marker meshes fail the quality checks");
  }
}
BENCHMARK(BM_BuildTileAndCheckMarkers)->Unit(benchmark::kMillisecond)->Iterations(2);

BENCHMARK_MAIN();
