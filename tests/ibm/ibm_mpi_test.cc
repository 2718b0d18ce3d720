// np = 2 vs np = 1: a moving sphere (prescribed rigid motion, multi-direct forcing, supports
// crossing the slab boundary) in a flow on MPI_COMM_WORLD (2 slabs) and on MPI_COMM_SELF (each
// rank alone): the same marker forces, slip, loads and velocity fields (run under mpirun -np 2;
// also passes with 1 rank).
#include <gtest/gtest.h>

#include <cmath>

#include "solver/fluid/fluid.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/loads.h"
#include "solver/ibm/plane_forcing.h"
#include "solver/ibm/shapes.h"

namespace systole::ibm {
namespace {

struct IbRun {
  grid::Grid grid{grid::BoxSpec{12, 12, 12, 1.5, 1.5, 1.5}};
  grid::Slabs slabs;
  fluid::FluidSolver fluid;
  Markers markers{grid};
  std::unique_ptr<DirectForcing> forcing;
  std::vector<Vec3> last_forces;
  IbRun(MPI_Comm comm, TransferKernel kernel) : slabs(grid, comm), fluid(slabs, parameters()) {
    BodyOptions o;
    o.mm_per_unit = 1.0;
    o.normals = ExpectedNormals::outward;
    o.retraction_cells = 0.3;  // round 2: retracted forcing points, surface probes
    // Centre at z = 0.75: on 2 ranks the slab boundary (k = 6, z = 0.75) cuts the sphere.
    const int b = markers.add_body(sphere_mesh(Vec3(0.7, 0.75, 0.75), 0.3, 2), "sphere", o);
    markers.set_rigid_motion(b, Vec3(0.2, 0, 0.1), Vec3(0, 0, 1.0), Vec3(0.7, 0.75, 0.75));
    ForcingParameters fp;
    fp.iterations = 2;
    fp.carry_over = true;  // round 2: the previous step's force carried over
    fp.kernel = kernel;
    forcing = std::make_unique<DirectForcing>(slabs, markers, fp);
    fluid.set_body_force([this](const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
      markers.advance_rigid(c.dt);
      forcing->markers_moved();
      forcing->apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w});
      last_forces = forcing->force_density();
    });
    fluid.set_velocity([](double, double, double z) { return 1.0 + 0.2 * std::sin(4 * z); },
                       [](double x, double, double) { return 0.1 * std::cos(4 * x); },
                       [](double, double, double) { return 0.0; });
  }
  static fluid::FluidParameters parameters() {
    fluid::FluidParameters p;
    p.reynolds = 50;
    p.bottom_wall.kind = p.top_wall.kind = fluid::WallKind::free_slip;
    return p;
  }
};

// MLS and the divergence-free kernel (its factored stencils, transfer.h).
class IbmDecompositionKernels : public ::testing::TestWithParam<TransferKernel> {};
INSTANTIATE_TEST_SUITE_P(IbmDecomposition, IbmDecompositionKernels,
                         ::testing::Values(TransferKernel::mls, TransferKernel::divergence_free),
                         [](const auto& info) { return info.param == TransferKernel::mls ? "mls" : "divergence_free"; });

TEST_P(IbmDecompositionKernels, OneAndTwoRanksGiveTheSameForcesLoadsAndFields) {
  IbRun world(MPI_COMM_WORLD, GetParam()), self(MPI_COMM_SELF, GetParam());
  for (IbRun* r : {&world, &self})
    for (int n = 0; n < 15; ++n) r->fluid.advance();
  ASSERT_EQ(world.fluid.time(), self.fluid.time());
  // Marker forces and slip: replicated, exactly equal.
  ASSERT_EQ(world.last_forces.size(), self.last_forces.size());
  double force_diff = 0, force_scale = 0;
  for (std::size_t b = 0; b < world.last_forces.size(); ++b) {
    force_diff = std::max(force_diff, (world.last_forces[b] - self.last_forces[b]).norm());
    force_scale = std::max(force_scale, self.last_forces[b].norm());
  }
  const auto& Vw = world.fluid.velocity();
  const auto& Vs = self.fluid.velocity();
  const SlipStats sw = world.forcing->slip({Vw.u, Vw.v, Vw.w}), ss = self.forcing->slip({Vs.u, Vs.v, Vs.w});
  const MarkerLoads lw = compute_loads(world.forcing->transfer(), {Vw.u, Vw.v, Vw.w}, world.fluid.pressure(), 50);
  const MarkerLoads ls = compute_loads(self.forcing->transfer(), {Vs.u, Vs.v, Vs.w}, self.fluid.pressure(), 50);
  // Fields: this rank's slab of the world run against the same planes of the serial run.
  const int k0 = world.slabs.k_begin();
  double field_diff = 0;
  for (int k = 0; k < Vw.u.k_count(); ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        field_diff = std::max(field_diff, std::abs(Vw.u(i, j, k) - Vs.u(i, j, k0 + k)));
        field_diff = std::max(field_diff, std::abs(Vw.v(i, j, k) - Vs.v(i, j, k0 + k)));
        field_diff = std::max(field_diff, std::abs(Vw.w(i, j, k) - Vs.w(i, j, k0 + k)));
      }
  double local[3] = {force_diff / force_scale, field_diff, (lw.total_force - ls.total_force).norm()}, worst[3];
  MPI_Allreduce(local, worst, 3, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  if (rank == 0)
    std::printf("  [measured] np=%d vs np=1: marker force %.3g (relative), fields %.3g, loads %.3g, slip rms %.6g vs %.6g\n",
                size, worst[0], worst[1], worst[2], sw.rms, ss.rms);
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_LT(worst[1], 1e-12);
  EXPECT_LT(worst[2], 1e-12);
  EXPECT_NEAR(sw.rms, ss.rms, 1e-14);
  EXPECT_GT(force_scale, 0.1);  // the forcing did something
}

// The seed's eq 4 plate (PlaneForcing) at z = 0.8 with a hole, on 2 slabs (boundary at z = 0.75):
// the w-node below the plane (z = 0.75, rank 1) takes x₂ from rank 0 through the halo.
struct PlaneRun {
  grid::Grid grid{grid::BoxSpec{12, 12, 12, 1.5, 1.5, 1.5}};
  grid::Slabs slabs;
  fluid::FluidSolver fluid;
  PlaneForcing plate;
  explicit PlaneRun(MPI_Comm comm)
      : slabs(grid, comm), fluid(slabs, IbRun::parameters()),
        plate(slabs, RigidPlane{2, 0.8, [](double x, double y) { return std::hypot(x - 0.7, y - 0.75) > 0.4; }}) {
    fluid.set_body_force([this](const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
      plate.apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, Vec3(0, 0, 1.0));
      for (int k = 0; k < f.w.k_count(); ++k)
        for (int j = 0; j < 12; ++j)
          for (int i = 0; i < 12; ++i)
            if (slabs.k_begin() + k > 0) f.w(i, j, k) += 1.0;  // drive through the hole
    });
    fluid.set_velocity([](double, double, double z) { return 0.3 * std::sin(4 * z); },
                       [](double x, double, double) { return 0.1 * std::cos(4 * x); },
                       [](double, double, double) { return 0.0; });
  }
};

TEST(IbmDecomposition, Eq4PlateIsTheSameOnOneAndTwoRanks) {
  PlaneRun world(MPI_COMM_WORLD), self(MPI_COMM_SELF);
  for (PlaneRun* r : {&world, &self})
    for (int n = 0; n < 15; ++n) r->fluid.advance();
  const auto& Vw = world.fluid.velocity();
  const auto& Vs = self.fluid.velocity();
  const int k0 = world.slabs.k_begin();
  double diff = 0, scale = 0;
  for (int k = 0; k < Vw.w.k_count(); ++k)
    for (int j = 0; j < 12; ++j)
      for (int i = 0; i < 12; ++i) {
        diff = std::max(diff, std::abs(Vw.u(i, j, k) - Vs.u(i, j, k0 + k)));
        diff = std::max(diff, std::abs(Vw.w(i, j, k) - Vs.w(i, j, k0 + k)));
        scale = std::max(scale, std::abs(Vs.w(i, j, k0 + k)));
      }
  double local[2] = {diff, scale}, worst[2];
  MPI_Allreduce(local, worst, 2, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("  [measured] eq 4 plate, np=2 vs np=1: fields %.3g (max |w| %.3g)\n", worst[0], worst[1]);
  EXPECT_LT(worst[0], 1e-12);
  EXPECT_GT(worst[1], 0.01);
}

}  // namespace
}  // namespace systole::ibm
