#pragma once
// In-process probes of the pieces a job goes through, to explain the end-to-end numbers:
// the disk's fdatasync, one SQLite WAL commit (synchronous=FULL as the store ships, and NORMAL
// as the alternative), JobStore::submit itself, the 0-D scene, the three result files the
// worker writes and uploads, and the mpirun launcher.
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "bench/service/stats.h"
#include "solver/core/run_result.h"

namespace systole::bench {

// write(4 KiB) + fdatasync(), n times, on a file in `dir`.
Summary probe_fdatasync(const std::filesystem::path& dir, int n);

// One BEGIN IMMEDIATE; INSERT (one ~300 byte row); COMMIT per sample, WAL mode, with the given
// PRAGMA synchronous value ("FULL", "NORMAL").
Summary probe_sqlite_commit(const std::filesystem::path& dir, const std::string& synchronous, int n);

// systole::store::JobStore::submit as the server calls it (its own pragmas).
Summary probe_jobstore_submit(const std::filesystem::path& dir, const std::string& scenario_json, int n);

struct SceneProbe {
  Summary validate_ms;                        // proto JSON → validated config (the worker does this per job)
  Summary run_ms;                             // scene::run
  Summary write_h5_ms;                        // result.h5
  Summary write_json_ms;                      // metrics.json
  Summary write_csv_ms;                       // pv_loop.csv
  Summary write_all_ms;                       // io::write_results (the three, as the worker calls it)
  std::map<std::string, int64_t> file_bytes;  // name → size
  size_t complete_request_bytes = 0;          // serialized CompleteJobRequest.result
  std::vector<std::filesystem::path> files;   // one set of result files, kept in out_dir
  RunResult result;                           // the last run
};
SceneProbe probe_scene(const std::string& scenario_json, const std::filesystem::path& out_dir, int reps);

// Wall time of `mpirun -np ranks /bin/true`: Open MPI's launcher alone (no MPI_Init; the
// throughput table's "workers ready after spawn" has the whole start-up of real workers).
Summary probe_mpirun(int ranks, int reps);

}  // namespace systole::bench
