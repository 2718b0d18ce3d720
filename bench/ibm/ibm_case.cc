// Runs one immersed-boundary verification case (solver/scene/ibm_scene.h) and prints its
// metrics as key = value lines. Usage:
//   ibm_case CASE [reynolds=20] [diameter_cells=10] [box_diameters=4] [box_length=12] [end_time=5] [iterations=1] [retraction=0] [eq4=0] [carry=0]
//            [frequency=1] [amplitude=0.01] [womersley=4] [cfl=0.2] [max_dt=0.02] [samples=50]
#include <mpi.h>

#include <cstdio>
#include <cstdlib>
#include <string>

#include "solver/scene/ibm_scene.h"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (argc < 2) {
    if (rank == 0) std::fprintf(stderr, "usage: ibm_case fixed_sphere|oscillating_sphere|womersley_pipe|orifice_plate [key=value...]\n");
    MPI_Finalize();
    return 2;
  }
  systole::scene::IbmCaseSpec s;
  s.case_name = systole::scene::parse_ibm_case(argv[1]);
  for (int a = 2; a < argc; ++a) {
    const std::string kv = argv[a];
    const auto eq = kv.find('=');
    const std::string k = kv.substr(0, eq);
    const double v = std::atof(kv.substr(eq + 1).c_str());
    if (k == "reynolds") s.reynolds = v;
    else if (k == "diameter_cells") s.diameter_cells = v;
    else if (k == "box_diameters") s.box_diameters = v;
    else if (k == "box_length") s.box_length_diameters = v;
    else if (k == "end_time") s.end_time = v;
    else if (k == "iterations") s.forcing_iterations = static_cast<int>(v);
    else if (k == "retraction") s.retraction_cells = v;
    else if (k == "eq4") s.first_node_plane = v != 0;
    else if (k == "carry") s.carry_over_force = v != 0;
    else if (k == "frequency") s.frequency = v;
    else if (k == "amplitude") s.amplitude = v;
    else if (k == "womersley") s.womersley_number = v;
    else if (k == "cfl") s.cfl = v;
    else if (k == "max_dt") s.max_dt = v;
    else if (k == "samples") s.samples = static_cast<int>(v);
    else {
      if (rank == 0) std::fprintf(stderr, "unknown key '%s'\n", k.c_str());
      MPI_Finalize();
      return 2;
    }
  }
  // Progress on stderr after each sample, so a long run shows its trend before it ends.
  const auto progress = [rank](const systole::ProgressReport& p) {
    if (rank != 0) return;
    std::fprintf(stderr, "progress t=%g fraction=%.3f %s\n", p.simulated_time_s, p.fraction, p.message.c_str());
    std::fflush(stderr);
  };
  const systole::RunResult r = systole::scene::run_ibm_case(s, MPI_COMM_WORLD, 1.0, progress);
  if (rank == 0) {
    for (const auto& [k, v] : r.metrics) std::printf("%s = %.6g\n", k.c_str(), v);
    if (const char* series = std::getenv("IBM_SERIES"); series && *series) {
      for (std::size_t i = 0; i < r.series[0].values.size(); ++i)
        std::printf("series %g %g %g %g\n", r.series[0].values[i], r.series[1].values[i], r.series[4].values[i],
                    r.series.size() > 5 ? r.series[5].values[i] : 0.0);
    }
  }
  MPI_Finalize();
  return 0;
}
