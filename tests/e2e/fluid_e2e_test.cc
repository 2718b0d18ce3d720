// systole-solve with scene "fluid": a small 2-D Taylor–Green vortex (32×32×8 cells, Re = 100,
// one time unit) serially and under mpirun -np 2 writes metrics.json with small error norms,
// equal between 1 and 2 ranks; bad input exits 2 naming the field.
#include "tests/e2e/harness.h"

namespace systole::e2e {
namespace {

nlohmann::json read_metrics(const fs::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "metrics.json")); }

fs::path write_fluid_scenario(const fs::path& dir) {
  // nx, ny, nz are grid points (cells + 1); nu = 1.44e-4 m²/s gives Re = U_m d_m / nu = 100;
  // 40 ms is one d_m / U_m.
  const nlohmann::json scenario{{"scene", "fluid"},
                                {"fluid",
                                 {{"verification_case", "taylor_green_2d"},
                                  {"nx", 33},
                                  {"ny", 33},
                                  {"nz", 9},
                                  {"kinematic_viscosity_m2_per_s", 1.44e-4},
                                  {"end_time_ms", 40},
                                  {"max_dt_ms", 0.4}}},
                                {"outputs", {{"time_series_interval_ms", 4}}}};
  const fs::path file = dir / "fluid-tg2d.json";
  std::ofstream(file) << scenario.dump(2);
  return file;
}

TEST(FluidE2E, SerialAndTwoRanksGiveTheSameSmallErrors) {
  const fs::path dir = make_temp_dir("fluid");
  const std::string solve = (bin_dir() / "systole-solve").string();
  const std::string scenario = write_fluid_scenario(dir).string();
  auto [c1, out1] = run_command(solve + " " + scenario + " --quiet --out " + (dir / "serial").string());
  ASSERT_EQ(c1, 0) << out1;
  auto [c2, out2] = run_command("OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 mpirun -np 2 --oversubscribe " +
                                solve + " " + scenario + " --quiet --out " + (dir / "mpi").string());
  ASSERT_EQ(c2, 0) << out2;
  const auto a = read_metrics(dir / "serial");
  const auto b = read_metrics(dir / "mpi");
  EXPECT_EQ(a["ranks"], 1);
  EXPECT_EQ(b["ranks"], 2);
  EXPECT_EQ(a["cells"], 32 * 32 * 8);
  EXPECT_DOUBLE_EQ(a["reynolds"].get<double>(), 100);
  // Second-order error of the 32² grid (3.1e-5 in fluid_verification_test), divergence at round-off.
  EXPECT_LT(a["error_l2_relative"].get<double>(), 1e-4);
  EXPECT_LT(a["error_linf_relative"].get<double>(), 2e-4);
  EXPECT_LT(a["max_divergence_all_steps"].get<double>(), 1e-11);
  EXPECT_LT(b["max_divergence_all_steps"].get<double>(), 1e-11);
  // The fields are bitwise equal between 1 and 2 ranks; norms summed over 2 slabs may differ
  // in the last bits (the order of the global sum).
  for (const char* key : {"error_l2_relative", "error_linf_relative", "kinetic_energy_final", "dissipation_final",
                          "mass_flux_relative_variation"}) {
    const double x = a[key].get<double>(), y = b[key].get<double>();
    EXPECT_NEAR(x, y, 1e-12 * std::max(std::abs(x), 1e-30) + 1e-20) << key;
  }
  for (const char* key : {"steps", "end_time", "last_dt", "cells"}) EXPECT_EQ(a[key], b[key]) << key;
  EXPECT_TRUE(fs::exists(dir / "mpi" / "result.h5"));
  fs::remove_all(dir);
}

TEST(FluidE2E, BadInputExitsTwoNamingTheField) {
  const fs::path dir = make_temp_dir("fluid-bad");
  const std::string solve = (bin_dir() / "systole-solve").string();
  const std::string scenario = write_fluid_scenario(dir).string();
  auto [code, output] = run_command(solve + " " + scenario + " --out " + (dir / "out").string() + " --set fluid.nx=3");
  EXPECT_EQ(code, 2) << output;
  EXPECT_NE(output.find("fluid.nx = 3 is out of range [8, 2049]"), std::string::npos) << output;
  auto [code2, output2] = run_command(solve + " " + scenario + " --out " + (dir / "out").string() +
                                      " --set fluid.viscosity_model=carreau_yasuda");
  EXPECT_EQ(code2, 2) << output2;
  EXPECT_NE(output2.find("fluid.viscosity_model = 'carreau_yasuda' needs fluid.verification_case = poiseuille or couette"),
            std::string::npos)
      << output2;
  EXPECT_FALSE(fs::exists(dir / "out" / "result.h5"));
  fs::remove_all(dir);
}

}  // namespace
}  // namespace systole::e2e
