// np = 2 vs np = 1: the same flow on MPI_COMM_WORLD (2 slabs) and on MPI_COMM_SELF (each rank
// alone) gives the same fields to 1e-12 (run under mpirun -np 2; also passes with 1 rank).
#include <gtest/gtest.h>

#include <mpi.h>

#include <cmath>
#include <filesystem>
#include <numbers>
#include <vector>

#include "solver/fluid/fluid.h"
#include "solver/grid/field_io.h"

namespace systole::fluid {
namespace {
constexpr double kPi = std::numbers::pi;

struct FluidRun {
  grid::Slabs slabs;
  FluidSolver fluid;
  FluidRun(MPI_Comm comm, const FluidParameters& p, const std::vector<double>& plane_weights = {})
      : slabs(grid::Grid({16, 12, 10, 2 * kPi, 2 * kPi, kPi}), comm, plane_weights), fluid(slabs, p) {}
};

void compare_one_and_two_ranks(const FluidParameters& p, const char* what, const std::vector<double>& weights = {});

TEST(Decomposition, OneAndTwoRanksGiveTheSameFields) {
  FluidParameters p;
  p.reynolds = 500;
  compare_one_and_two_ranks(p, "newtonian");
}

// Carreau–Yasuda: ν needs its halos from the neighbour slab and its wall ghosts on both.
TEST(Decomposition, OneAndTwoRanksGiveTheSameFieldsShearThinning) {
  FluidParameters p;
  p.viscosity_model = "carreau_yasuda";
  p.carreau_yasuda = {0.01, 0.002, 3.0, 0.5, 1.5};
  compare_one_and_two_ranks(p, "carreau_yasuda");
}

// Vreman's eddy viscosity: the gradient reads the neighbour slab's faces, ν its halos and ghosts.
TEST(Decomposition, OneAndTwoRanksGiveTheSameFieldsVreman) {
  FluidParameters p;
  p.reynolds = 500;
  p.subgrid_model = "vreman";
  compare_one_and_two_ranks(p, "vreman");
}

// Slabs split by weight (grid::weighted_ranges, fsei.slab_split = "balanced"): 2 ranks own 8
// and 2 of the 10 planes; the transposes, halos and walls still give the one-rank fields.
TEST(Decomposition, UnevenSlabsGiveTheSameFields) {
  const std::vector<double> weights{1, 1, 1, 1, 1, 1, 1, 5, 5, 5};
  const grid::Slabs probe(grid::Grid({16, 12, 10, 2 * kPi, 2 * kPi, kPi}), MPI_COMM_WORLD, weights);
  if (probe.size() == 2) {
    EXPECT_EQ(probe.z_range(0).count, 8);
    EXPECT_EQ(probe.z_range(1).count, 2);
  }
  FluidParameters p;
  p.reynolds = 500;
  compare_one_and_two_ranks(p, "uneven slabs", weights);
}

void compare_one_and_two_ranks(const FluidParameters& parameters, const char* what, const std::vector<double>& weights) {
  FluidParameters p = parameters;
  p.top_wall.velocity_x = 0.3;  // no-slip, moving: exercises the wall ghosts and the body force
  p.darcy_regions.push_back({0, 2 * kPi, 0, 2 * kPi, 1.0, 1.5});
  auto u0 = [](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::sin(z); };
  auto v0 = [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::sin(z) + 0.1 * std::cos(2 * x); };
  auto w0 = [](double x, double, double z) { return 0.2 * std::sin(x) * std::sin(z); };
  auto force = [](const StepContext& c, const Velocity&, Velocity& f) {
    for (int k = 0; k < f.u.k_count(); ++k)
      for (int j = 0; j < f.u.ny(); ++j)
        for (int i = 0; i < f.u.nx(); ++i) f.u(i, j, k) = 0.1 * std::cos(c.time + 0.3 * j + 0.1 * (f.u.k_begin() + k));
  };
  FluidRun world(MPI_COMM_WORLD, p, weights), self(MPI_COMM_SELF, p);
  for (FluidRun* r : {&world, &self}) {
    r->fluid.set_body_force(force);
    r->fluid.set_velocity(u0, v0, w0);
    for (int n = 0; n < 25; ++n) r->fluid.advance();
  }
  EXPECT_EQ(world.fluid.time(), self.fluid.time());
  const int k0 = world.slabs.k_begin();
  double worst = 0;
  const Velocity &a = world.fluid.velocity(), &b = self.fluid.velocity();
  for (int k = 0; k < a.u.k_count(); ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 16; ++i)
        worst = std::max({worst, std::abs(a.u(i, j, k) - b.u(i, j, k0 + k)), std::abs(a.v(i, j, k) - b.v(i, j, k0 + k)),
                          std::abs(a.w(i, j, k) - b.w(i, j, k0 + k))});
  // Pressure is defined up to a constant: compare differences to cell (0,0,0).
  double p_ref_world = 0, p_ref_self = self.fluid.pressure()(0, 0, 0);
  if (world.slabs.rank() == 0) p_ref_world = world.fluid.pressure()(0, 0, 0);
  MPI_Bcast(&p_ref_world, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  for (int k = 0; k < a.u.k_count(); ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 16; ++i)
        worst = std::max(worst, std::abs((world.fluid.pressure()(i, j, k) - p_ref_world) -
                                         (self.fluid.pressure()(i, j, k0 + k) - p_ref_self)));
  double global = 0;
  MPI_Allreduce(&worst, &global, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  if (world.slabs.rank() == 0) std::printf("  [measured] %s: max |np=2 − np=1| = %.3g\n", what, global);
  EXPECT_LE(global, 1e-12);
}

// Field output with units and compression (FieldSelection scales, gzip): on the slabs of all
// ranks (np 2: HDF5's collective writes of filtered datasets), the compressed, scaled file reads
// back as the scales times the plain file, bitwise, and is smaller.
TEST(FieldOutput, CompressedScaledFieldsReadBackAsTheScaledPlainOnes) {
  FluidParameters p;
  p.reynolds = 500;
  FluidRun run(MPI_COMM_WORLD, p);
  run.fluid.set_velocity([](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); },
                         [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); },
                         [](double, double, double) { return 0.0; });
  for (int n = 0; n < 3; ++n) run.fluid.advance();
  const auto dir = std::filesystem::temp_directory_path();
  const auto plain = dir / "systole_fields_plain.h5", packed = dir / "systole_fields_packed.h5";
  FluidSolver::FieldSelection units;
  units.write_xdmf = false;
  run.fluid.write_fields(plain, units);
  units.velocity_scale = 0.6;
  units.pressure_scale = 2.862;
  units.vorticity_scale = 25;
  units.gzip_level = 4;
  run.fluid.write_fields(packed, units);
  const grid::FieldFile a(plain, run.slabs, grid::FieldFile::Mode::read), b(packed, run.slabs, grid::FieldFile::Mode::read);
  long differences = 0;
  for (const auto& [name, scale] : {std::pair{"velocity_x", 0.6}, std::pair{"velocity_z", 0.6}, std::pair{"pressure", 2.862},
                                    std::pair{"vorticity_y", 25.0}}) {
    grid::CellField fa(run.slabs), fb(run.slabs);
    a.read(name, fa);
    b.read(name, fb);
    for (int k = 0; k < fa.k_count(); ++k)
      for (int j = 0; j < 12; ++j)
        for (int i = 0; i < 16; ++i) differences += fb(i, j, k) != fa(i, j, k) * scale;
  }
  EXPECT_EQ(differences, 0);
  MPI_Barrier(MPI_COMM_WORLD);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) {
    EXPECT_LT(std::filesystem::file_size(packed), std::filesystem::file_size(plain));
  }
}

}  // namespace
}  // namespace systole::fluid
