// Verification tier of the immersed boundary with the fluid (solver/scene/ibm_scene.h):
// observed orders asserted as numbers.
#include <gtest/gtest.h>

#include <map>

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
// interface), measured over every sample of the period. retraction: r_d of markers.h.
std::map<std::string, double> womersley_metrics(double diameter_cells, double retraction) {
  IbmCaseSpec s;
  s.case_name = IbmCase::womersley_pipe;
  s.reynolds = 100;
  s.womersley_number = 4;
  s.diameter_cells = diameter_cells;
  s.end_time = 1;  // one period
  s.samples = 10;
  s.retraction_cells = retraction;
  return run_ibm_case(s, MPI_COMM_WORLD).metrics;
}
double womersley_error(double diameter_cells, double retraction) {
  return womersley_metrics(diameter_cells, retraction).at("error_linf_relative");
}

TEST(IbmWomersleyPipe, ConvergesAtFirstOrder) {
  double previous = 0;
  for (double dc : {10.0, 20.0}) {
    const double e = womersley_error(dc, 0.0);
    print("womersley pipe D/h = " + std::to_string(static_cast<int>(dc)) + ", markers on the wall: max error / peak", e);
    if (previous > 0) {
      const double order = std::log2(previous / e);
      print("  observed order", order);
      EXPECT_GE(order, 0.8);
    }
    previous = e;
  }
}

// The same with the markers retracted by r_d = 0.5 h out of the lumen (markers.h; Breugem 2012).
// r_d is not fitted to this flow: it is the offset of the diffuse MLS wall measured on the plane
// channel (IbmRigidPlane.MlsAndEq4PlatesPoiseuilleWallOffsetAndEquivalence: 0.454, 0.476, 0.483 h).
// Issue 7's goal, within 5 % of the analytic peak, is met at D/h = 20 (measured 0.042; 0.164
// without the retraction), still converging at first order.
TEST(IbmWomersleyPipe, RetractedMarkersWithinFivePercentAtTwentyCells) {
  const auto m10 = womersley_metrics(10, 0.5), m20 = womersley_metrics(20, 0.5);
  const double coarse = m10.at("error_linf_relative"), fine = m20.at("error_linf_relative");
  print("womersley pipe D/h = 10, r_d = 0.5: max error / peak", coarse);
  print("womersley pipe D/h = 20, r_d = 0.5: max error / peak", fine);
  print("  observed order", std::log2(coarse / fine));
  EXPECT_GE(std::log2(coarse / fine), 0.8);
  EXPECT_LT(fine, 0.05);
  // The wall shear stress of eq 27 at the markers, extrapolated to the wall from probes at h
  // and 2h (ibm::wall_shear_stress), against Womersley's exact Re^-1 |du/dr(R, t)|: at least
  // first order (the IB's velocity is), and closer than the loads' single probe h off the wall.
  const double w10 = m10.at("wall_shear_error_linf_relative"), w20 = m20.at("wall_shear_error_linf_relative");
  const double p10 = m10.at("wall_shear_probe_error_linf_relative"), p20 = m20.at("wall_shear_probe_error_linf_relative");
  print("  wall shear stress D/h = 10: max error / amplitude", w10);
  print("  wall shear stress D/h = 20: max error / amplitude", w20);
  print("  observed order", std::log2(w10 / w20));
  print("  single probe h off the wall, D/h = 10", p10);
  print("  single probe h off the wall, D/h = 20", p20);
  EXPECT_GE(std::log2(w10 / w20), 0.8);
  EXPECT_LT(w10, p10);
  EXPECT_LT(w20, p20);
}

// The rigid valvular plane with one opening (scene case orifice_plate, D/h = 8, Re = 10, duct
// 3 × 3 × 3): flow through the hole while it is open; at t = 2 the cover is switched on (the
// seed's vein ostia, MODEL.md §2) and the flow through the duct must stop. Both plates: the
// seed's eq 4 (plane_forcing.h) and MLS markers with the force carried over (forcing.h; with the
// seed's single pass the MLS plate leaks under the pressure jump, docs/ibm.md).
RunResult orifice(bool eq4) {
  IbmCaseSpec s;
  s.case_name = IbmCase::orifice_plate;
  s.reynolds = 10;
  s.diameter_cells = 8;
  s.box_diameters = 3;
  s.end_time = 4;
  s.samples = 16;
  s.first_node_plane = eq4;
  s.carry_over_force = !eq4;
  s.retraction_cells = eq4 ? 0.0 : 0.5;
  return run_ibm_case(s, MPI_COMM_WORLD);
}

TEST(IbmOrifice, CoverSwitchedOnStopsTheFlowThroughTheHole) {
  for (bool eq4 : {true, false}) {
    const RunResult r = orifice(eq4);
    const std::string name = eq4 ? "eq 4 plate" : "MLS plate (carry-over, rim r_d = 0.5)";
    print(name + ": flow rate open (t = 2)", r.metrics.at("flow_rate_open"));
    print(name + ": flow rate with the cover on (t = 4)", r.metrics.at("flow_rate_closed"));
    print(name + ": closed / open", r.metrics.at("closed_to_open_flow_ratio"));
    EXPECT_GT(r.metrics.at("flow_rate_open"), 0.3);  // measured 0.76 (eq 4), 0.51 (MLS)
    EXPECT_LT(std::abs(r.metrics.at("closed_to_open_flow_ratio")), 0.01);  // measured 3e-4, 9e-5
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
