// systole-solve: runs a scenario's scene locally, without the service, and writes the same
// outputs as a job (result.h5, metrics.json, pv_loop.csv). Also runs under mpirun (every rank
// runs the scene, rank 0 writes). Tests and benchmarks use it.
//   systole-solve SCENARIO.json --out DIR [--checkpoint-dir DIR] [--set path=value ...]
//   systole-solve --list-parameters        (the Markdown reference, docs/parameters.md)
//   systole-solve --list-scenes            (the scene registry: name, metric count, description)
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>

#include <CLI/CLI.hpp>

#include "proto/bridge/scenario_bridge.h"
#include "solver/config/parameter_table.h"
#include "solver/core/allocator.h"
#include "solver/core/errors.h"
#include "solver/core/threads.h"
#include "solver/io/result_writer.h"
#include "solver/scene/registry.h"
#include "solver/scene/scene.h"

using namespace systole;

namespace {

class ConsoleControl final : public scene::RunControl {
 public:
  ConsoleControl(int rank, bool quiet, std::filesystem::path out, std::filesystem::path checkpoint)
      : rank_(rank), quiet_(quiet), out_(std::move(out)), checkpoint_(std::move(checkpoint)) {}
  std::filesystem::path output_directory() override { return out_; }
  std::filesystem::path checkpoint_directory() override { return checkpoint_; }
  void on_progress(const ProgressReport& p) override {
    if (rank_ != 0 || quiet_) return;
    std::cerr << "beat " << p.beat << "/" << p.beats_total << "  t = " << std::fixed << std::setprecision(3)
              << p.simulated_time_s << " s";
    for (const char* key : {"ejection_fraction_percent", "edv_ml", "cardiac_output_l_min"}) {
      auto it = p.latest_beat_metrics.find(key);
      if (it != p.latest_beat_metrics.end()) std::cerr << "  " << key << " = " << std::setprecision(3) << it->second;
    }
    if (!p.message.empty()) std::cerr << "  " << p.message;
    std::cerr << "\n";
  }
  bool cancel_requested() override { return false; }

 private:
  int rank_;
  bool quiet_;
  std::filesystem::path out_, checkpoint_;
};

// The scene registry (solver/scene/registry.h) as a table: one line per scene.
void print_scenes(std::ostream& out) {
  out << std::left << std::setw(18) << "scene" << std::right << std::setw(7) << "metrics" << "  description\n";
  for (const scene::SceneEntry& e : scene::scene_registry())
    out << std::left << std::setw(18) << e.name << std::right << std::setw(7) << e.metric_names().size() << "  "
        << e.description << "\n";
}

}  // namespace

int main(int argc, char** argv) {
  const bool heap_policy = systole::keep_freed_memory_in_heap();  // before any large array
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (!heap_policy && rank == 0)
    std::cerr << "systole-solve: warning: glibc refused the heap policy (solver/core/allocator.h); "
                 "large runs will be slower, their values are unchanged\n";
  CLI::App app{"systole-solve: run a systole scenario locally and write its results"};
  std::string file, out_dir, checkpoint_dir;
  std::vector<std::string> sets;
  bool list_parameters = false, list_scenes = false, quiet = false;
  app.add_option("scenario", file, "scenario JSON file (proto3 JSON)");
  app.add_option("--out", out_dir, "output directory");
  app.add_option("--checkpoint-dir", checkpoint_dir,
                 "scenes fsi/fsei: keep checkpoints here (every fsei.checkpoint_interval_ms) and resume from one "
                 "found here");
  app.add_option("--set", sets, "override a field: path.to.field=value (repeatable)");
  app.add_flag("--list-parameters", list_parameters, "print the parameter reference (Markdown) and exit");
  app.add_flag("--list-scenes", list_scenes, "print the scenes (name, metric count, description) and exit");
  app.add_flag("--quiet", quiet, "no per-beat progress on stderr");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = rank == 0 ? app.exit(e) : 1;
    MPI_Finalize();
    return code;
  }
  const OpenMpThreads omp = share_cores_among_ranks(MPI_COMM_WORLD);  // collective; solver/core/threads.h
  if (rank == 0 && !quiet && !list_parameters && !list_scenes) std::cerr << "systole-solve: " << omp.describe() << "\n";
  int code = 0;
  try {
    if (list_parameters) {
      if (rank == 0) std::cout << config::parameters_markdown();
    } else if (list_scenes) {
      if (rank == 0) print_scenes(std::cout);
    } else {
      if (file.empty() || out_dir.empty()) throw InputError("usage: systole-solve SCENARIO.json --out DIR [--set path=value ...]");
      const config::Scenario scenario = bridge::validate(bridge::load_scenario_file(file, sets));
      ConsoleControl control(rank, quiet, out_dir, checkpoint_dir);
      RunResult result = scene::run(scenario, control);
      if (rank == 0) {
        const auto files = io::write_results(out_dir, result, {config::to_json(scenario).dump(), ""});
        std::cout << std::fixed << std::setprecision(2);
        const auto& listed = scene::metric_names(scenario.scene);
        for (const auto& key : listed) {
          const auto it = result.metrics.find(key);
          if (it != result.metrics.end()) std::cout << std::left << std::setw(32) << key << " " << it->second << "\n";
        }
        // Then what this run reported beyond the scene's fixed list (a protocol's or a body's own
        // metrics), at most 40 of them.
        int extra = 0, more = 0;
        for (const auto& [key, value] : result.metrics) {
          if (std::find(listed.begin(), listed.end(), key) != listed.end()) continue;
          if (++extra <= 40)
            std::cout << std::left << std::setw(32) << key << " " << std::defaultfloat << std::setprecision(6) << value
                      << "\n";
          else ++more;
        }
        if (more > 0) std::cout << "(" << more << " more in metrics.json)\n";
        for (const auto& f : files) std::cout << "wrote " << f.string() << "\n";
      }
    }
  } catch (const InputError& e) {
    if (rank == 0) std::cerr << "systole-solve: " << e.what() << "\n";
    code = 2;
  } catch (const InstabilityError& e) {
    if (rank == 0) std::cerr << "systole-solve: " << e.what() << "\n";
    code = 3;
  } catch (const std::exception& e) {
    if (rank == 0) std::cerr << "systole-solve: " << e.what() << "\n";
    code = 1;
  }
  MPI_Finalize();
  return code;
}
