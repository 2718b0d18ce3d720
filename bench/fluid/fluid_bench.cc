// fluid_bench NX NY NZ [STEPS] [carreau_yasuda]: cells (the seed's grid 1, "129×129×145"
// points, is 128 128 144). Box 95×95×140 mm in d_m = 24 mm units, Re = 3000 (or the blood
// Carreau–Yasuda law), a 3-D Taylor–Green-like start, adaptive Δt.
// Prints one line per run (rank 0). The byte count is a model: the arrays each stage streams
// (8-byte reads + writes, write-allocate counted), per cell; see solver/fluid/README.md.
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "solver/fluid/fluid.h"

namespace {
using Clock = std::chrono::steady_clock;

// STREAM triad a = b + s c on 3 × 32 MB arrays per rank, all ranks at once; best of 5; GB/s
// summed over ranks, counting 3 × 8 bytes per element (+ write-allocate: 4 × 8).
double stream_triad_gb_s(MPI_Comm comm) {
  const std::size_t n = 4 << 20;
  std::vector<double> a(n, 0), b(n, 1), c(n, 2);
  double best = 1e30;
  for (int rep = 0; rep < 5; ++rep) {
    MPI_Barrier(comm);
    const auto t0 = Clock::now();
    for (std::size_t i = 0; i < n; ++i) a[i] = b[i] + 3.0 * c[i];
    MPI_Barrier(comm);
    best = std::min(best, std::chrono::duration<double>(Clock::now() - t0).count());
  }
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  volatile double sink = a[n / 2];
  (void)sink;
  return ranks * 3.0 * 8.0 * n / best / 1e9;
}

// Doubles streamed per cell per step, by stage (write-allocate counted on written arrays).
struct Stage {
  const char* name;
  double doubles;
};
constexpr Stage kTraffic[] = {
    {"explicit terms (read u,v,w; write H×3)", 9},
    {"AB2 predictor (read u,v,w,p,H×3,H'×3; write u,v,w)", 13},
    {"divergence (read u,v,w; write r)", 5},
    {"Poisson: copies, FFT r2c/c2r, 2×2 transposes, Thomas", 35},
    {"gradient correction (read φ,u,v,w; write u,v,w)", 7},
    {"pressure update (read p,φ; write p)", 3},
    {"stability check (read u,v,w)", 3},
};
// Extra traffic of the Carreau–Yasuda viscosity (per cell-step).
constexpr Stage kShearThinningTraffic[] = {
    {"viscosity (read u,v,w; write nu) + halo", 5},
    {"variable viscous term (read u,v,w,nu; read+write H×3)", 10},
};
}  // namespace

void run(int rank, int ranks, int nx, int ny, int nz, int steps, bool shear_thinning);

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (argc < 4) {
    if (rank == 0) std::fprintf(stderr, "usage: fluid_bench NX NY NZ [STEPS] [carreau_yasuda]\n");
    MPI_Finalize();
    return 2;
  }
  const int nx = std::atoi(argv[1]), ny = std::atoi(argv[2]), nz = std::atoi(argv[3]);
  const int steps = argc > 4 ? std::atoi(argv[4]) : 20;
  const bool shear_thinning = argc > 5 && std::string(argv[5]) == "carreau_yasuda";
  run(rank, ranks, nx, ny, nz, steps, shear_thinning);
  MPI_Finalize();
  return 0;
}

void run(int rank, int ranks, int nx, int ny, int nz, int steps, bool shear_thinning) {
  using namespace systole;
  const double lx = 95.0 / 24, ly = 95.0 / 24, lz = 140.0 / 24;
  const grid::Slabs slabs(grid::Grid({nx, ny, nz, lx, ly, lz}), MPI_COMM_WORLD);
  fluid::FluidParameters p;
  p.reynolds = 3000;
  if (shear_thinning) p.viscosity_model = "carreau_yasuda";  // blood (Cho & Kensey 1991)
  fluid::FluidSolver f(slabs, p);
  const double kx = 2 * M_PI / lx, ky = 2 * M_PI / ly, kz = M_PI / lz;
  f.set_velocity([&](double x, double y, double z) { return std::sin(kx * x) * std::cos(ky * y) * std::sin(kz * z); },
                 [&](double x, double y, double z) { return -std::cos(kx * x) * std::sin(ky * y) * std::sin(kz * z); },
                 [](double, double, double) { return 0.0; });
  for (int n = 0; n < 3; ++n) f.advance();  // warm-up (AB2 history, caches, MPI)
  MPI_Barrier(MPI_COMM_WORLD);
  const auto t0 = Clock::now();
  for (int n = 0; n < steps; ++n) f.advance();
  MPI_Barrier(MPI_COMM_WORLD);
  const double seconds = std::chrono::duration<double>(Clock::now() - t0).count() / steps;
  const double triad = stream_triad_gb_s(MPI_COMM_WORLD);
  double bytes_local = static_cast<double>(f.bytes_allocated()), bytes = 0;
  MPI_Reduce(&bytes_local, &bytes, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  const double cells = static_cast<double>(slabs.grid().cells());
  double doubles_per_cell = 0;
  for (const auto& s : kTraffic) doubles_per_cell += s.doubles;
  if (shear_thinning)
    for (const auto& s : kShearThinningTraffic) doubles_per_cell += s.doubles;
  const double moved = doubles_per_cell * 8 * cells;
  const double bound = moved / (triad * 1e9);
  if (rank == 0) {
    std::printf(
        "grid %dx%dx%d cells, %s, %d rank(s): %.3f ms/step, %.1f ns/cell-step, %.0f B/cell-step moved "
        "(%.2f GB/step) -> %.2f GB/s effective; STREAM triad %.1f GB/s -> bandwidth bound %.3f ms/step, "
        "measured/bound = %.2f; memory %.0f B/cell (%.1f MB); dt = %.3g; poisson self-test %.2g\n",
        nx, ny, nz, shear_thinning ? "carreau_yasuda" : "newtonian", ranks, seconds * 1e3, seconds * 1e9 / cells, doubles_per_cell * 8, moved / 1e9,
        moved / seconds / 1e9, triad, bound * 1e3, seconds / bound, bytes / cells, bytes / 1e6, f.last_dt(),
        f.poisson().self_test_relative_divergence());
  }
}
