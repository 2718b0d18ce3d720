// Verification tier of the immersed boundary with the fluid (solver/scene/ibm_scene.h):
// observed orders asserted as numbers.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <vector>

#include <unistd.h>

#include "solver/core/errors.h"
#include "solver/scene/ibm_scene.h"

namespace systole::scene {
namespace {

void print(const std::string& what, double value) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) std::printf("  [measured] %s = %.6g\n", what.c_str(), value);
}

IbmCaseSpec sphere(double diameter_cells, int iterations) {
  IbmCaseSpec s;
  s.case_name = IbmCase::fixed_sphere;
  s.reynolds = 20;
  s.diameter_cells = diameter_cells;
  s.box_diameters = 3;
  s.box_length_diameters = 6;
  s.end_time = 2.0;
  s.samples = 10;
  s.forcing_iterations = iterations;
  return s;
}

// Slip |V_b − u(X_b)| of the end-of-step (projected) velocity at the markers of a fixed
// sphere at Re = 20, rms over the markers, averaged over the samples t ∈ [1, 2] D/U (one
// instant of the start-up transient is noisy), on three grids: first order in h. The box has
// an even number of cells on every grid, so the sphere sits at the same place relative to the
// nodes (an odd count moves it by half a cell and changes the slip pattern).
TEST(IbmSlip, DecreasesWithRefinementAtFirstOrder) {
  // The observed order is the least-squares slope of log(slip) against log(D/h) over the three
  // grids (the icosphere's subdivision level steps between D/h = 8 and 12, so pairwise orders
  // scatter around it: measured 0.67 and 1.25).
  std::vector<double> lx, ly;
  double previous = 1e300;
  for (double dc : {6.0, 8.0, 12.0}) {
    const RunResult r = run_ibm_case(sphere(dc, 1), MPI_COMM_WORLD);
    const double slip = r.metrics.at("slip_rms_mean");
    print("fixed sphere Re 20, D/h = " + std::to_string(static_cast<int>(dc)) + ": slip rms (mean over t in [1,2])", slip);
    EXPECT_LT(r.metrics.at("max_divergence_final"), 1e-11);
    EXPECT_LT(slip, previous);
    previous = slip;
    lx.push_back(std::log(dc));
    ly.push_back(std::log(slip));
  }
  const double mx = (lx[0] + lx[1] + lx[2]) / 3, my = (ly[0] + ly[1] + ly[2]) / 3;
  double sxy = 0, sxx = 0;
  for (int i = 0; i < 3; ++i) {
    sxy += (lx[i] - mx) * (ly[i] - my);
    sxx += (lx[i] - mx) * (lx[i] - mx);
  }
  const double order = -sxy / sxx;
  print("observed slip order (least squares, D/h = 6, 8, 12)", order);
  EXPECT_GE(order, 0.8);
}

// Multi-direct forcing: 3 passes cut the end-of-step slip by more than half (measured ≈ 5×).
TEST(IbmSlip, MultiDirectForcingReducesSlip) {
  const double one = run_ibm_case(sphere(8, 1), MPI_COMM_WORLD).metrics.at("slip_rms_final");
  const double three = run_ibm_case(sphere(8, 3), MPI_COMM_WORLD).metrics.at("slip_rms_final");
  print("slip rms, 1 forcing pass", one);
  print("slip rms, 3 forcing passes", three);
  EXPECT_LT(three, 0.5 * one);
}

// Womersley flow in a tube of IB markers (Wo = 4, Re = 100), one period from the analytic
// periodic state: the max error inside the tube converges at first order (the diffuse
// interface), measured over every sample of the period.
TEST(IbmWomersleyPipe, ConvergesAtFirstOrder) {
  double previous = 0;
  for (double dc : {10.0, 20.0}) {
    IbmCaseSpec s;
    s.case_name = IbmCase::womersley_pipe;
    s.reynolds = 100;
    s.womersley_number = 4;
    s.diameter_cells = dc;
    s.end_time = 1;  // one period
    s.samples = 10;
    const RunResult r = run_ibm_case(s, MPI_COMM_WORLD);
    const double e = r.metrics.at("error_linf_relative");
    print("womersley pipe D/h = " + std::to_string(static_cast<int>(dc)) + ": max error / peak", e);
    if (previous > 0) {
      const double order = std::log2(previous / e);
      print("  observed order", order);
      EXPECT_GE(order, 0.8);
    }
    previous = e;
  }
}

TEST(IbmCases, WritesFieldsAndMarkersWhenAsked) {
  IbmCaseSpec s = sphere(6, 1);
  s.end_time = 0.1;
  const auto dir = std::filesystem::temp_directory_path() / ("ibm_fields_test_" + std::to_string(::getpid()));
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  s.output_dir = dir;
  const RunResult r = run_ibm_case(s, MPI_COMM_WORLD);
  EXPECT_EQ(r.metrics.at("fields_written"), 1);
  if (rank == 0) {
    EXPECT_TRUE(std::filesystem::exists(dir / "ibm_fields.h5"));
    EXPECT_TRUE(std::filesystem::exists(dir / "ibm_fields.xmf"));
    EXPECT_GT(std::filesystem::file_size(dir / "ibm_markers.csv"), 100u);
    std::filesystem::remove_all(dir);
  }
}

TEST(IbmCases, BadInputNamesTheField) {
  IbmCaseSpec s = sphere(8, 1);
  s.diameter_cells = 2;
  try {
    run_ibm_case(s, MPI_COMM_WORLD);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ibm.diameter_cells = 2"), std::string::npos);
  }
  EXPECT_THROW(parse_ibm_case("cylinder"), InputError);
  s = sphere(8, 1);
  s.forcing_iterations = 0;
  EXPECT_THROW(run_ibm_case(s, MPI_COMM_WORLD), InputError);
}

}  // namespace
}  // namespace systole::scene
