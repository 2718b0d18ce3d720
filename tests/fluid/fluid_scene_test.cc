// Scene "fluid" (solver/scene): the scenario → FluidCaseSpec mapping, field output through
// RunControl::output_directory(), cancellation, and the low-Re and shear-thinning verification
// flows reached through scenario parameters alone.
#include <gtest/gtest.h>
#include <mpi.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/fluid/verification_cases.h"
#include "solver/scene/scene.h"

namespace systole::scene {
namespace {
namespace fs = std::filesystem;

class Control final : public RunControl {
 public:
  explicit Control(fs::path dir = {}, int cancel_after = -1) : dir_(std::move(dir)), cancel_after_(cancel_after) {}
  void on_progress(const ProgressReport& r) override {
    ++reports;
    last = r;
  }
  bool cancel_requested() override { return cancel_after_ >= 0 && ++polls > cancel_after_; }
  fs::path output_directory() override { return dir_; }
  int reports = 0, polls = 0;
  ProgressReport last;

 private:
  fs::path dir_;
  int cancel_after_;
};

config::Scenario fluid_scenario(nlohmann::json fluid, nlohmann::json outputs = nlohmann::json::object()) {
  return config::parse_scenario({{"scene", "fluid"}, {"fluid", std::move(fluid)}, {"outputs", std::move(outputs)}});
}

// Every rank sees the same directory: rank 0 picks it, the others receive it.
fs::path shared_temp_dir(const std::string& tag) {
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  std::string name = (fs::temp_directory_path() / ("systole_fluid_scene_" + tag + "_" + std::to_string(::getpid())))
                         .string();
  int size = static_cast<int>(name.size());
  MPI_Bcast(&size, 1, MPI_INT, 0, MPI_COMM_WORLD);
  name.resize(size);
  MPI_Bcast(name.data(), size, MPI_CHAR, 0, MPI_COMM_WORLD);
  return name;
}

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(FluidScene, MapsTheScenarioOntoTheVerificationCase) {
  // nx, ny, nz are points (cells + 1); Re = U_m d_m / nu; one time unit is 40 ms.
  const auto s = fluid_scenario({{"nx", 33}, {"ny", 33}, {"nz", 9}, {"kinematic_viscosity_m2_per_s", 1.44e-4},
                                 {"end_time_ms", 40}, {"max_dt_ms", 0.4}},
                                {{"time_series_interval_ms", 4}});
  Control control;
  const RunResult r = run(s, control);
  fluid::FluidCaseSpec spec;
  spec.nx = spec.ny = 32;
  spec.nz = 8;
  spec.reynolds = 0.6 * 0.024 / 1.44e-4;
  spec.end_time = 1.0;
  spec.max_dt = 0.01;
  spec.samples = 10;
  spec.viscosity_model = "newtonian";
  const RunResult direct = fluid::run_verification_case(spec, MPI_COMM_WORLD);
  EXPECT_NEAR(r.metrics.at("reynolds"), 100, 1e-9);
  EXPECT_EQ(r.metrics.at("cells"), 32 * 32 * 8);
  EXPECT_EQ(r.metrics.at("end_time"), 1.0);
  EXPECT_EQ(r.metrics.at("error_l2_relative"), direct.metrics.at("error_l2_relative"));
  EXPECT_LT(r.metrics.at("error_l2_relative"), 1e-4);
  EXPECT_EQ(r.metrics.count("cancelled"), 0u);
  EXPECT_EQ(r.metrics.at("fields_written"), 0);
  EXPECT_EQ(control.reports, 10);
  EXPECT_NEAR(control.last.simulated_time_s, 0.04, 1e-12);
  ASSERT_FALSE(r.series.empty());
  EXPECT_EQ(r.series[0].values.size(), 11u);  // t = 0 and the 10 samples
}

TEST(FluidScene, WritesFieldsIntoTheCallersDirectory) {
  const fs::path dir = shared_temp_dir("fields");
  {
    const auto s = fluid_scenario({{"nx", 17}, {"ny", 17}, {"nz", 9}, {"end_time_ms", 4}, {"write_fields", true}});
    Control control(dir);
    const RunResult r = run(s, control);
    EXPECT_EQ(r.metrics.at("fields_written"), 1);
    EXPECT_TRUE(fs::exists(dir / "fluid_fields.h5"));
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) {
      const std::string xmf = read_text(dir / "fluid_fields.xmf");
      for (const char* name : {"velocity", "pressure", "vorticity"}) EXPECT_NE(xmf.find(name), std::string::npos) << name;
    }
  }
  {
    // outputs.fields selects a subset; without fluid.write_fields only those are written.
    const auto s = fluid_scenario({{"nx", 17}, {"ny", 17}, {"nz", 9}, {"end_time_ms", 4}}, {{"fields", {"pressure"}}});
    Control control(dir);
    const RunResult r = run(s, control);
    EXPECT_EQ(r.metrics.at("fields_written"), 1);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0) {
      const std::string xmf = read_text(dir / "fluid_fields.xmf");
      EXPECT_NE(xmf.find("pressure"), std::string::npos);
      EXPECT_EQ(xmf.find("velocity"), std::string::npos);
    }
  }
  {
    // Fields asked for, but the caller keeps no files: nothing written, said in a note.
    const auto s = fluid_scenario({{"nx", 17}, {"ny", 17}, {"nz", 9}, {"end_time_ms", 4}, {"write_fields", true}});
    Control control;
    const RunResult r = run(s, control);
    EXPECT_EQ(r.metrics.at("fields_written"), 0);
    bool noted = false;
    for (const auto& n : r.notes) noted = noted || n.find("no output directory") != std::string::npos;
    EXPECT_TRUE(noted);
  }
  MPI_Barrier(MPI_COMM_WORLD);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0) fs::remove_all(dir);
}

TEST(FluidScene, CancelThrowsCancelled) {
  const auto s = fluid_scenario({{"nx", 17}, {"ny", 17}, {"nz", 9}, {"end_time_ms", 20}});
  Control control({}, 2);
  EXPECT_THROW(run(s, control), Cancelled);
}

TEST(FluidScene, BadCombinationsAreInputErrors) {
  auto error_of = [](const nlohmann::json& fluid) {
    try {
      (void)fluid_scenario(fluid);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(error_of({{"viscosity_model", "carreau_yasuda"}}).find("needs fluid.verification_case = poiseuille or couette"),
            std::string::npos);
  EXPECT_NE(error_of({{"viscosity_model", "carreau_yasuda"}, {"carreau_yasuda_mu_inf_pa_s", 0.1}})
                .find("fluid.carreau_yasuda_mu_inf_pa_s = 0.1 must not exceed fluid.carreau_yasuda_mu0_pa_s = 0.056"),
            std::string::npos);
  EXPECT_NE(error_of({{"nx", 3}}).find("fluid.nx = 3 is out of range [8, 2049]"), std::string::npos);
  EXPECT_NE(error_of({{"verification_case", "kovasznay"}}).find("unknown fluid.verification_case 'kovasznay'"),
            std::string::npos);
}

// The low-Re flows of the verification suite through scenario parameters alone: Newtonian
// Poiseuille at Re = 10 (nu = 1.44e-3 m²/s), and the shear-thinning Poiseuille of
// fluid_verification_test (ν0* = 0.1, ν∞* = 0.02, λ* = 1, n = 0.5, G = 8/Re = 1) in SI units:
// μ = ν* ρ U_m d_m with ρ U_m d_m = 15.264 Pa·s, λ = λ* d_m / U_m = 0.04 s, Re = 8 ↔ nu = 1.8e-3.
TEST(FluidScene, LowReynoldsAndShearThinningPoiseuilleFromRest) {
  {
    const auto s = fluid_scenario({{"verification_case", "poiseuille"}, {"nx", 8}, {"ny", 8}, {"nz", 17},
                                   {"kinematic_viscosity_m2_per_s", 1.44e-3}, {"end_time_ms", 560}},
                                  {{"time_series_interval_ms", 56}});
    Control control;
    const RunResult r = run(s, control);
    EXPECT_NEAR(r.metrics.at("reynolds"), 10, 1e-9);
    EXPECT_LT(r.metrics.at("error_linf_relative"), 1.1 / (16 * 16));  // Δz², as in fluid_verification_test
  }
  {
    const auto s = fluid_scenario({{"verification_case", "poiseuille"}, {"nx", 8}, {"ny", 8}, {"nz", 17},
                                   {"kinematic_viscosity_m2_per_s", 1.8e-3}, {"viscosity_model", "carreau_yasuda"},
                                   {"carreau_yasuda_mu0_pa_s", 0.1 * 15.264}, {"carreau_yasuda_mu_inf_pa_s", 0.02 * 15.264},
                                   {"carreau_yasuda_lambda_s", 0.04}, {"carreau_yasuda_n", 0.5},
                                   {"end_time_ms", 960}},
                                  {{"time_series_interval_ms", 96}});
    Control control;
    const RunResult r = run(s, control);
    int rank = 0;
    MPI_Comm_rank(MPI_COMM_WORLD, &rank);
    if (rank == 0)
      std::printf("  [measured] scene fluid, carreau_yasuda poiseuille nz=16 from rest: Linf error %.4g, peak %.6g\n",
                  r.metrics.at("error_linf_relative"), r.metrics.at("reference_peak_velocity"));
    EXPECT_GT(r.metrics.at("max_viscosity"), 0.09);  // near ν0* = 0.1 in the cells by the centre line
    EXPECT_LE(r.metrics.at("max_viscosity"), 0.1);
    EXPECT_LT(r.metrics.at("error_linf_relative"), 0.01);    // 7.4e-3 at steady state (nz = 16)
    EXPECT_NEAR(r.metrics.at("reference_peak_velocity"), 1.91132 * 1.25, 1e-4);  // 1.91132 × 1/(8ν0)
  }
}

}  // namespace
}  // namespace systole::scene
