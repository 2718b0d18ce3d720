// The regression tier (docs/verification.md, "Test tiers"): short runs of the coupled scenes
// compared value by value with reference files stored in tests/regression/data/ (every series
// point and metric, 17 digits; tests/coupling/run_values.h). A plain MPI program:
//   regression_test write CASE FILE     runs CASE and writes its values (how a reference is made)
//   regression_test compare CASE FILE   runs CASE and compares with FILE
// A value passes when |a - b| / (|a| + 1) <= kTolerance; wall times are not compared. On the
// machine and build that wrote a reference the runs agree bitwise; the tolerance admits the
// round-off of another compiler or MPI over these few milliseconds, not a change of the physics
// (which moves these values by far more: a changed default moves them at 1e-3 or more).
// The references' origin: tests/regression/data/README.md.
#include <mpi.h>

#include <cstdio>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

#include "solver/config/scenario.h"
#include "solver/scene/scene.h"
#include "tests/coupling/run_values.h"

using namespace systole;

namespace {

constexpr double kTolerance = 1e-9;

class Quiet final : public scene::RunControl {
 public:
  void on_progress(const ProgressReport&) override {}
  bool cancel_requested() override { return false; }
};

// The cases: the first 3 ms of the coarse heart in blood at the scenes' defaults (fsi: the
// prescribed tension; fsei: with its EP), sampled every 0.5 ms; one coarse electromechanics beat
// (examples/electromechanics_coarse.json without its field frames).
nlohmann::json case_scenario(const std::string& name) {
  if (name == "fsi_coarse_3ms" || name == "fsei_coarse_3ms")
    return {{"scene", name.substr(0, name.find('_'))},
            {"fsei", {{"end_time_ms", 3.0}}},
            {"outputs", {{"time_series_interval_ms", 0.5}}}};
  if (name == "electromechanics_beat")
    return {{"scene", "electromechanics"},
            {"beats", 1},
            {"geometry", {{"target_edge_mm", 3}}},
            {"electro", {{"model", "monodomain"}, {"time_step_ms", 0.1}}},
            {"electromechanics", {{"sync_step_ms", 1.0}}}};
  throw std::runtime_error("unknown case " + name + "; known: fsi_coarse_3ms, fsei_coarse_3ms, electromechanics_beat");
}

bool skip(const std::string& key) { return key.find("wall_s") != std::string::npos || key == "metric:wall_time_s"; }

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  int status = 0;
  try {
    const std::string mode = argc == 4 ? argv[1] : "";
    if (mode != "write" && mode != "compare") throw std::runtime_error("usage: regression_test write|compare CASE FILE");
    const std::string name = argv[2], file = argv[3];
    Quiet control;
    const RunResult r = scene::run(config::parse_scenario(case_scenario(name)), control);
    if (rank == 0) {
      if (mode == "write") {
        test::write_values(file, test::values_of(r));
        std::printf("%s: %zu values written to %s\n", name.c_str(), test::values_of(r).size(), file.c_str());
      } else {
        const test::Comparison c =
            test::compare_values(test::read_values(file), test::values_of(r), kTolerance, skip, "reference", "this run");
        std::printf("%s: %d values compared, %d beyond %.0e; largest difference %.3g at %s\n", name.c_str(), c.compared,
                    c.bad, kTolerance, c.worst, c.worst_name.c_str());
        status = c.bad == 0 ? 0 : 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "regression_test (rank %d): %s\n", rank, e.what());
    status = 1;
  }
  MPI_Bcast(&status, 1, MPI_INT, 0, MPI_COMM_WORLD);
  MPI_Finalize();
  return status;
}
