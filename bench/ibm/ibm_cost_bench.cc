// Cost of the immersed-boundary stages per marker per step on the default left heart
// (solver/geometry build_left_heart, every body, markers at 0.7 h) on the seed's grid 1
// (128×128×144 cells) and grid 2 (192×192×256 cells): stencil rebuild (moving bodies), velocity
// (all bodies moved; and the check that skips unmoved bodies), velocity
// interpolation, spreading, one direct-forcing pass (interpolate + spread), loads (probes with
// MLS gradients, eq 11–14, 27). One rank, OMP_NUM_THREADS threads; best of `repeats` timings, wall and
// CPU (user + system of the process) side by side. Usage: ibm_cost_bench [repeats=3] [grids=2]
// [kernel=mls|divergence_free] (the transfer's weights, transfer.h: MLS's 27 per marker and
// component, or the divergence-free kernel's three 1-D factors)
#include <mpi.h>

#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/loads.h"

namespace {
using namespace systole;
double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
struct Timing {
  double wall = 1e300, cpu = 1e300;  // best of the repeats (each taken separately)
};
Timing best_seconds(int repeats, const std::function<void()>& f) {
  Timing best;
  for (int r = 0; r < repeats; ++r) {
    const double c0 = cpu_seconds();
    const auto t0 = std::chrono::steady_clock::now();
    f();
    best.wall = std::min(best.wall, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    best.cpu = std::min(best.cpu, cpu_seconds() - c0);
  }
  return best;
}
}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  const int repeats = argc > 1 ? std::atoi(argv[1]) : 3;
  const int grids = argc > 2 ? std::atoi(argv[2]) : 2;
  const std::string kernel_name = argc > 3 ? argv[3] : "mls";
  if (kernel_name != "mls" && kernel_name != "divergence_free") {
    std::fprintf(stderr, "ibm_cost_bench: kernel = \"%s\": use mls or divergence_free\n", kernel_name.c_str());
    MPI_Finalize();
    return 2;
  }
  ibm::ForcingParameters forcing_parameters;
  forcing_parameters.kernel = kernel_name == "mls" ? ibm::TransferKernel::mls : ibm::TransferKernel::divergence_free;
  const config::Scenario sc = config::default_scenario();
  const geometry::LeftHeart heart = geometry::build_left_heart(sc.geometry, sc.fluid);
  const double unit_mm = 24.0;  // d_m
  struct G { const char* name; int nx, ny, nz; };
  int grid_index = 0;
  for (const G& gs : {G{"grid 1", 128, 128, 144}, G{"grid 2", 192, 192, 256}}) {
    if (++grid_index > grids) break;
    const grid::Grid g({gs.nx, gs.ny, gs.nz, sc.fluid.box_x_mm / unit_mm, sc.fluid.box_y_mm / unit_mm,
                        sc.fluid.box_z_mm / unit_mm});
    const grid::Slabs slabs(g, MPI_COMM_WORLD);
    ibm::Markers markers(g);
    for (const geometry::TriMesh& body : heart.bodies) {
      ibm::BodyOptions o;
      o.mm_per_unit = unit_mm;
      o.sides = body.kind == geometry::BodyKind::kLeaflet ? ibm::Sides::two : ibm::Sides::one;
      markers.add_body(body, body.name, o);
    }
    grid::XFaceField u(slabs), fu(slabs);
    grid::YFaceField v(slabs), fv(slabs);
    grid::ZFaceField w(slabs), fw(slabs);
    grid::CellField p(slabs);
    u.fill(0.3);
    v.fill(-0.1);
    w.fill(0.2);
    p.fill(1.0);
    ibm::DirectForcing forcing(slabs, markers, forcing_parameters);
    const double n = static_cast<double>(markers.size());
    std::vector<ibm::Vec3> F(markers.size(), ibm::Vec3(1, 2, 3));
    ibm::Transfer& t = const_cast<ibm::Transfer&>(forcing.transfer());
    // Every body moved (the heart's deformable bodies do, each step); and nothing moved (the
    // check that skips unchanged bodies: fixed ones such as the valvular plane).
    const Timing rebuild = best_seconds(repeats, [&] { t.rebuild_all(); });
    const Timing unchanged = best_seconds(repeats, [&] { (void)t.rebuild(); });
    const Timing interp = best_seconds(repeats, [&] { (void)t.interpolate({u, v, w}); });
    const Timing spread = best_seconds(repeats, [&] { t.spread(F, {fu, fv, fw}); });
    const Timing apply = best_seconds(repeats, [&] { forcing.apply(0.01, {u, v, w}, {fu, fv, fw}); });
    const Timing loads = best_seconds(repeats, [&] { (void)ibm::compute_loads(t, {u, v, w}, p, 3000); });
    // The carry-over's anti-windup mask (2 h, the heart's tight setting) after the markers moved:
    // markers_moved() on unmoved markers is the mask plus the rebuild's unmoved check.
    ibm::ForcingParameters carry = forcing_parameters;
    carry.carry_over = true;
    carry.carry_over_exclusion_cells = 2;
    ibm::DirectForcing carrying(slabs, markers, carry);
    const Timing mask = best_seconds(repeats, [&] { carrying.markers_moved(); });
    // The loads' probes alone (MLS pressure and velocity gradient at X + h n, and X − h n for the
    // leaflets): the rest of "loads + WSS" is eq 11/12/14, the nodal forces and the WSS (eq 27).
    std::vector<ibm::Vec3> points;
    {
      const ibm::MarkerArrays& m = markers.markers();
      for (std::size_t b = 0; b < markers.size(); ++b) {
        points.push_back(m.surface[b] + markers.h() * m.normal[b]);
        if (markers.bodies()[static_cast<std::size_t>(m.body[b])].options.sides == ibm::Sides::two)
          points.push_back(m.surface[b] - markers.h() * m.normal[b]);
      }
    }
    const Timing probes = best_seconds(repeats, [&] { (void)ibm::probe(t, {u, v, w}, p, points); });
    std::printf("%s (%d x %d x %d cells, h = %.4f mm), kernel %s: %zu markers in %zu bodies\n", gs.name, gs.nx, gs.ny,
                gs.nz, markers.h() * unit_mm, kernel_name.c_str(), markers.size(), markers.bodies().size());
    for (const auto& b : markers.bodies())
      std::printf("   %-18s tiling level %d, %zu markers\n", b.name.c_str(), b.tiling_level, b.marker_count);
    auto line = [&](const char* what, const Timing& t) {
      std::printf("  %-17s wall %9.3f ms  %7.1f ns/marker | cpu %9.3f ms  %7.1f ns/marker\n", what, 1e3 * t.wall,
                  1e9 * t.wall / n, 1e3 * t.cpu, 1e9 * t.cpu / n);
    };
    line("stencil rebuild", rebuild);
    line("rebuild, unmoved", unchanged);
    line("interpolation", interp);
    line("spreading", spread);
    line("forcing pass", apply);
    line("loads + WSS", loads);
    line("carry-over mask", mask);
    std::printf("    (2 h exclusion: %zu markers excluded)\n", carrying.carry_over_excluded());
    std::printf("    of which probes   wall %9.3f ms (%zu probes) | cpu %9.3f ms; eq 11-14 + nodal forces + WSS: cpu %.3f ms\n",
                1e3 * probes.wall, points.size(), 1e3 * probes.cpu, 1e3 * (loads.cpu - probes.cpu));
    std::printf("  IB stage (rebuild + forcing + loads) wall %8.3f ms, cpu %8.3f ms per step\n",
                1e3 * (rebuild.wall + apply.wall + loads.wall), 1e3 * (rebuild.cpu + apply.cpu + loads.cpu));
  }
  MPI_Finalize();
  return 0;
}
