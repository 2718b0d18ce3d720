// Runs scene "fsei" or "fsi" (solver/scene/fsei_scene.h) from the default scenario with
// path=value overrides, prints every sample on stderr as it comes (so a run that stops with a
// diagnosis leaves its trend) and the metrics on stdout: how the scenes are studied.
//   fsei_case fsi|fsei [out=DIR] [checkpoint=DIR] [fsei.end_time_ms=16] [fsei.resolution=coarse] ...
// out=DIR: the output directory: the result files (result.h5, metrics.json, time_series.csv, ...)
// at the end, field frames with fsei.field_interval_ms > 0 or outputs.field_phases.
// checkpoint=DIR: checkpoints every fsei.checkpoint_interval_ms into DIR, and a resume from
// the one found there (docs/fsei.md, "Checkpoint and restart"); with out=DIR, each checkpoint
// also rewrites DIR/time_series.partial.csv (the series so far, for fsei_beats while it runs).
#include <cstdio>
#include <filesystem>
#include <string>

#include <mpi.h>

#include "solver/config/scenario.h"
#include "solver/core/allocator.h"
#include "solver/core/errors.h"
#include "solver/core/threads.h"
#include "solver/io/result_writer.h"
#include "solver/scene/fsei_scene.h"

namespace {
class Printer final : public systole::scene::RunControl {
 public:
  Printer(int rank, std::filesystem::path out, std::filesystem::path checkpoint)
      : rank_(rank), out_(std::move(out)), checkpoint_(std::move(checkpoint)) {}
  std::filesystem::path output_directory() override { return out_; }
  std::filesystem::path checkpoint_directory() override { return checkpoint_; }
  void on_progress(const systole::ProgressReport& r) override {
    if (rank_ != 0) return;
    std::fprintf(stderr, "%s\n", r.message.c_str());
    std::fflush(stderr);
  }
  bool cancel_requested() override { return false; }
  // A running job's series (rank 0, out=DIR only): rewritten at each checkpoint as
  // DIR/time_series.partial.csv, for bench/coupling/fsei_beats; removed when the run ends with its
  // results (time_series.csv), left for a run that stops. A failed write is reported, not fatal.
  void on_checkpoint(const systole::RunResult& so_far) override {
    if (rank_ != 0 || out_.empty() || so_far.series.empty()) return;
    try {
      systole::io::write_time_series_csv(partial_series_file(), so_far);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "fsei_case: warning: %s not written: %s\n", partial_series_file().c_str(), e.what());
    }
  }
  std::filesystem::path partial_series_file() const { return out_ / "time_series.partial.csv"; }

 private:
  int rank_;
  std::filesystem::path out_, checkpoint_;
};
}  // namespace

int main(int argc, char** argv) {
  const bool heap_policy = systole::keep_freed_memory_in_heap();  // before any large array
  MPI_Init(&argc, &argv);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (!heap_policy && rank == 0)
    std::fprintf(stderr, "fsei_case: warning: glibc refused the heap policy (solver/core/allocator.h): slower, same values\n");
  const systole::OpenMpThreads omp = systole::share_cores_among_ranks(MPI_COMM_WORLD);  // solver/core/threads.h
  if (rank == 0) std::fprintf(stderr, "fsei_case: %s\n", omp.describe().c_str());
  int rc = 0;
  try {
    if (argc < 2 || (std::string(argv[1]) != "fsi" && std::string(argv[1]) != "fsei"))
      throw systole::InputError("usage: fsei_case fsi|fsei [path=value ...]");
    nlohmann::json doc = nlohmann::json::object();
    std::filesystem::path out, checkpoint;
    for (int a = 2; a < argc; ++a) {
      const std::string arg = argv[a];
      if (arg.rfind("out=", 0) == 0) out = arg.substr(4);
      else if (arg.rfind("checkpoint=", 0) == 0) checkpoint = arg.substr(11);
      else systole::config::apply_override(doc, arg);
    }
    doc["scene"] = argv[1];
    const systole::config::Scenario s = systole::config::parse_scenario(doc);
    // The directories are made (or refused) before the run, not at its end: a run of an hour once lost its
    // outputs to a missing out=DIR (session 38). Every rank makes them (idempotent), so every rank agrees.
    for (const auto& [name, dir] : {std::pair<const char*, std::filesystem::path>{"out", out}, {"checkpoint", checkpoint}}) {
      if (dir.empty()) continue;
      std::error_code ec;
      std::filesystem::create_directories(dir, ec);
      if (!std::filesystem::is_directory(dir))
        throw systole::InputError(std::string(name) + "=" + dir.string() + ": cannot make the directory" +
                                  (ec ? " (" + ec.message() + ")" : std::string()) + "; allowed: a writable directory path");
    }
    Printer control(rank, out, checkpoint);
    const systole::RunResult r = systole::scene::run_fsei(s, control);
    if (rank == 0) {
      for (const auto& [k, v] : r.metrics) std::printf("%s = %.6g\n", k.c_str(), v);
      for (const auto& n : r.notes) std::printf("note: %s\n", n.c_str());
      // out=DIR also gets the job's result files (result.h5 with the per-beat metrics and phase
      // averages, metrics.json, time_series.csv, ...), as systole-solve --out writes them
      if (!out.empty())
        for (const auto& f : systole::io::write_results(out, r, {systole::config::to_json(s).dump(), ""}))
          std::printf("wrote %s\n", f.c_str());
      std::error_code ignored;  // none written (no checkpoint) is fine
      if (!out.empty()) std::filesystem::remove(control.partial_series_file(), ignored);
    }
  } catch (const std::exception& e) {
    if (rank == 0) std::fprintf(stderr, "fsei_case: %s\n", e.what());
    rc = 1;
  }
  MPI_Finalize();
  return rc;
}
