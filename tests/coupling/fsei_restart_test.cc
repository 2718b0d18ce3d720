// Scenes "fsi"/"fsei": checkpoint and restart (issue #9, "a run continued from a checkpoint is
// bitwise identical to a straight run; restart also works on a different rank count"). A plain
// MPI program run three times by ctest, on the coarse heart with the aorta's ground pressure
// (the blood moving at once), 1 ms, sampled every 0.2 ms, fields every 0.5 ms:
//   fsei_restart_test straight SCENE CKDIR OUTDIR FILE  (1 rank) the straight run, checkpoints
//       every 0.6 ms into CKDIR (one, at 0.6 ms); writes every series value and metric to FILE;
//   fsei_restart_test resume|resume-fresh SCENE CKDIR OUTDIR FILE  (1 or 2 ranks) the same
//       scenario with CKDIR: it must resume at 0.6 ms; compares with FILE: on 1 rank every value
//       bitwise, on 2 ranks within 1e-12 (|a| + 1) (the partitions reorder sums: round-off, as
//       in fsei_ranks_test). Timings (*_wall_s, wall_time_s) are not compared.
// The resumed run's fields: "resume" writes into the straight run's OUTDIR, where the frames
// continue (3 frames: 0, 0.5, 1 ms; the one at 1 ms is written again); "resume-fresh" empties
// OUTDIR first: the frames before the checkpoint are left out of the xmf, with a note.
// SCENE fsi_carry_over: fsi with the tight setting's numerics: fsei.forcing.carry_over (the
// carried force is checkpointed), strong IQN-ILS coupling (its secant columns are) and
// fsei.sync_interval = fluid_step (the intervals follow the fluid's restored velocities).
// SCENE fsi_structure_first / fsei_structure_first: fsi_carry_over's numerics on fsi / fsei with
// fsei.coupling_order = structure_first: the loads last written are checkpointed (the shells
// use them in the next interval's first pass) and fsi's scene clock is restored.
// SCENE fsi_linear_guess: fsi_structure_first with fsei.first_pass_predictor = linear: the loads
// of the interval before the last and the last interval's length are checkpointed too.
#include <mpi.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "solver/config/scenario.h"
#include "solver/scene/fsei_scene.h"
#include "tests/coupling/run_values.h"

using namespace systole;

namespace {

class Control final : public scene::RunControl {
 public:
  Control(std::filesystem::path out, std::filesystem::path checkpoint)
      : out_(std::move(out)), checkpoint_(std::move(checkpoint)) {}
  void on_progress(const ProgressReport&) override {}
  bool cancel_requested() override { return false; }
  std::filesystem::path output_directory() override { return out_; }
  std::filesystem::path checkpoint_directory() override { return checkpoint_; }

 private:
  std::filesystem::path out_, checkpoint_;
};

// SCENE "fsi_carry_over": scene fsi with the carry-over forcing, whose carried force is state,
// strong IQN-ILS coupling and intervals following the fluid's step.
RunResult run_case(const std::string& scene, const std::filesystem::path& out, const std::filesystem::path& checkpoint) {
  const bool linear_guess = scene.ends_with("_linear_guess");
  const bool structure_first = scene.ends_with("_structure_first") || linear_guess;
  const bool carry_over = scene == "fsi_carry_over" || structure_first;
  const std::string base = scene.starts_with("fsei") ? "fsei" : "fsi";
  nlohmann::json doc = {
      {"scene", base},
      {"fsei",
       {{"end_time_ms", 1.0}, {"checkpoint_interval_ms", 0.6}, {"field_interval_ms", 0.5}, {"forcing", {{"carry_over", carry_over}}}}},
      {"outputs", {{"time_series_interval_ms", 0.2}}}};
  doc["fsei"]["defaults"] = "seed";  // each case names its numerics on the table's defaults
  if (carry_over) {
    doc["fsei"]["strong_coupling"] = true;
    doc["fsei"]["sync_interval"] = "fluid_step";
    doc["coupling"] = {{"relaxation", "iqn_ils"}, {"strong_tolerance", 1e-2}, {"strong_max_iterations", 12}};
  }
  if (structure_first) doc["fsei"]["coupling_order"] = "structure_first";
  if (linear_guess) doc["fsei"]["first_pass_predictor"] = "linear";
  const config::Scenario s = config::parse_scenario(doc);
  Control control(out, checkpoint);
  return scene::run_fsei(s, control);
}

bool has_note(const RunResult& r, const std::string& text) {
  for (const auto& n : r.notes)
    if (n.find(text) != std::string::npos) return true;
  return false;
}

std::string read_text(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int status = 0;
  try {
    const std::string m = argc > 1 ? argv[1] : "";
    if (argc != 6 || (m != "straight" && m != "resume" && m != "resume-fresh"))
      throw std::runtime_error("usage: fsei_restart_test straight|resume|resume-fresh SCENE CKDIR OUTDIR FILE");
    const std::string mode = argv[1], scene = argv[2], file = argv[5];
    const std::filesystem::path ckdir = argv[3], outdir = argv[4];
    if (mode == "straight") {
      if (rank == 0) {
        std::filesystem::remove_all(ckdir);
        std::filesystem::remove_all(outdir);
      }
      MPI_Barrier(MPI_COMM_WORLD);
      const RunResult r = run_case(scene, outdir, ckdir);
      if (rank == 0) {
        if (!has_note(r, "1 checkpoints written")) throw std::runtime_error("the straight run wrote no checkpoint");
        if (r.metrics.at("resumed_from_ms") != 0) throw std::runtime_error("the straight run says it resumed");
        if (!std::filesystem::exists(ckdir / "latest" / "state.h5")) throw std::runtime_error("no checkpoint in " + ckdir.string());
        // fluid_step intervals: the fluid takes one step per coupling pass
        std::printf("%s: %.0f coupling passes in %.0f intervals\n", scene.c_str(), r.metrics.at("coupling_passes"),
                    r.metrics.at("coupling_intervals"));
        if (scene != "fsi" && scene != "fsei" && r.metrics.at("fluid_steps") != r.metrics.at("coupling_passes"))
          throw std::runtime_error("fsei.sync_interval = fluid_step: " + std::to_string(r.metrics.at("fluid_steps")) +
                                   " fluid steps in " + std::to_string(r.metrics.at("coupling_passes")) + " passes");
        test::write_values(file, test::values_of(r));
        std::printf("straight run: %zu values written to %s\n", test::values_of(r).size(), file.c_str());
      }
    } else {
      if (mode == "resume-fresh" && rank == 0) std::filesystem::remove_all(outdir);
      MPI_Barrier(MPI_COMM_WORLD);
      const RunResult r = run_case(scene, outdir, ckdir);
      if (rank == 0) {
        int bad = 0;
        if (!has_note(r, "resumed from the checkpoint at t = 0.6 ms") || std::abs(r.metrics.at("resumed_from_ms") - 0.6) > 1e-9) {
          std::printf("  the run did not resume from the checkpoint at 0.6 ms\n");
          ++bad;
        }
        // the fields: continued in the straight run's directory, or a new one (see the header)
        const std::string xmf = read_text(outdir / "fsei_fields.xmf");
        const bool continued = mode == "resume";
        const bool frames_ok = continued ? xmf.find("\"frame2\"") != std::string::npos && xmf.find("\"frame3\"") == std::string::npos &&
                                               xmf.find("\"frame0\"") != std::string::npos
                                         : xmf.find("\"frame2\"") != std::string::npos && xmf.find("\"frame0\"") == std::string::npos &&
                                               has_note(r, "not in this output directory");
        if (!frames_ok) {
          std::printf("  the field frames are not as expected (%s directory)\n", continued ? "continued" : "new");
          ++bad;
        }
        const double tolerance = size == 1 ? 0.0 : 1e-12;
        const auto skip = [](const std::string& key) {
          return key.find("wall_s") != std::string::npos || key == "metric:wall_time_s" || key == "metric:resumed_from_ms";
        };
        const test::Comparison c = test::compare_values(test::read_values(file), test::values_of(r), tolerance, skip,
                                                        "straight", "resumed (np " + std::to_string(size) + ")");
        bad += c.bad;
        std::printf("resumed on %d rank(s) vs straight: %d values compared, largest |a - b| / (|a| + 1) = %.3g (%s), "
                    "allowed %.0e; %d failures\n",
                    size, c.compared, c.worst, c.worst_name.c_str(), tolerance, bad);
        status = bad == 0 && c.compared > 50 ? 0 : 1;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fsei_restart_test (rank %d): %s\n", rank, e.what());
    status = 1;
  }
  int worst = 0;
  MPI_Allreduce(&status, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  MPI_Finalize();
  return worst;
}
