// Runs the membrane sphere of solver/scene/rigs/fsi_sphere.h with options given as key=value and
// prints V/V0 over time and the run's counts (docs/fsei.md, the leak and stability table).
//   fsi_sphere_case [cells=32] [carry_over=1] [forcing_iterations=1] [strong=0] [end_ms=60] ...
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>

#include <mpi.h>

#include "solver/core/errors.h"
#include "solver/scene/rigs/fsi_sphere.h"

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  systole::scene::FsiSphereOptions o;
  std::map<std::string, double*> real{{"reynolds", &o.reynolds},
                                      {"radius_mm", &o.radius_mm},
                                      {"thickness_mm", &o.thickness_mm},
                                      {"stiffness_scale", &o.stiffness_scale},
                                      {"stretch", &o.stretch},
                                      {"marker_retraction_cells", &o.marker_retraction_cells},
                                      {"marker_spacing_fraction", &o.marker_spacing_fraction},
                                      {"sync_step_ms", &o.sync_step_ms},
                                      {"carry_over_factor", &o.carry_over_factor},
                                      {"end_ms", &o.end_ms},
                                      {"sample_ms", &o.sample_ms}};
  std::map<std::string, int*> integer{{"cells", &o.cells},
                                      {"icosphere_level", &o.icosphere_level},
                                      {"forcing_iterations", &o.forcing_iterations},
                                      {"strong_passes", &o.strong_passes}};
  std::map<std::string, bool*> flag{{"carry_over", &o.carry_over},
                                    {"strong", &o.strong_coupling},
                                    {"divergence_free_kernel", &o.divergence_free_kernel}};
  int rc = 0;
  try {
    for (int a = 1; a < argc; ++a) {
      const std::string kv = argv[a];
      const auto eq = kv.find('=');
      if (eq == std::string::npos) throw systole::InputError("expected key=value, got '" + kv + "'");
      const std::string k = kv.substr(0, eq);
      const double v = std::atof(kv.c_str() + eq + 1);
      if (real.count(k)) *real[k] = v;
      else if (integer.count(k)) *integer[k] = static_cast<int>(v);
      else if (flag.count(k)) *flag[k] = v != 0;
      else throw systole::InputError("unknown key '" + k + "'");
    }
    const auto r = systole::scene::run_fsi_sphere(o, MPI_COMM_WORLD);
    if (rank == 0) {
      for (std::size_t k = 0; k < r.time_ms.size(); ++k) std::printf("t %.1f ms  V/V0 %.4f\n", r.time_ms[k], r.volume_ratio[k]);
      std::printf("min %.4f max %.4f  fluid steps %lld  shell substeps %lld  passes %lld  unconverged %lld  "
                  "mean wall pressure %.4g\n",
                  r.min_volume_ratio, r.max_volume_ratio, r.fluid_steps, r.shell_substeps, r.passes,
                  r.unconverged_intervals, r.mean_wall_pressure);
      const double lost = r.initial_volume_mm3 * (1 - r.volume_ratio.back());
      std::printf("volume lost %.4g mm3 (%.3f %%); sampled every %g ms: through the markers (slip) %.4g mm3, swept by "
                  "the markers' velocities %.4g mm3\n",
                  lost, 100 * lost / r.initial_volume_mm3, o.sample_ms, r.slip_volume_mm3, r.told_volume_mm3);
      if (!r.stopped.empty()) std::printf("stopped: %s\n", r.stopped.c_str());
    }
  } catch (const std::exception& e) {
    if (rank == 0) std::fprintf(stderr, "fsi_sphere_case: %s\n", e.what());
    rc = 2;
  }
  MPI_Finalize();
  return rc;
}
