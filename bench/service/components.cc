#include "bench/service/components.h"

#include <fcntl.h>
#include <sqlite3.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <stdexcept>

#include "bench/service/bench_server.h"
#include "proto/bridge/scenario_bridge.h"
#include "service/store/job_store.h"
#include "solver/config/scenario.h"
#include "solver/io/result_writer.h"
#include "solver/scene/scene.h"
#include "worker/result_proto.h"

namespace systole::bench {

namespace {

void sqlite_exec(sqlite3* db, const std::string& sql) {
  char* error = nullptr;
  if (sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &error) != SQLITE_OK) {
    const std::string message = error ? error : "?";
    sqlite3_free(error);
    throw std::runtime_error("sqlite: " + sql + ": " + message);
  }
}

class NoControl final : public scene::RunControl {
 public:
  void on_progress(const ProgressReport&) override {}
  bool cancel_requested() override { return false; }
};

template <class F>
double time_ms(F&& f) {
  const auto t0 = Clock::now();
  f();
  return ms_since(t0);
}

}  // namespace

Summary probe_fdatasync(const fs::path& dir, int n) {
  const fs::path file = dir / "fdatasync.probe";
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd < 0) throw std::runtime_error("cannot create " + file.string());
  std::string block(4096, 'x');
  std::vector<double> samples;
  for (int i = 0; i < n; ++i) {
    samples.push_back(time_ms([&] {
      if (::pwrite(fd, block.data(), block.size(), static_cast<off_t>(i % 64) * 4096) < 0)
        throw std::runtime_error("pwrite failed");
      ::fdatasync(fd);
    }));
  }
  ::close(fd);
  fs::remove(file);
  return summarize(samples);
}

Summary probe_sqlite_commit(const fs::path& dir, const std::string& synchronous, int n) {
  const fs::path file = dir / ("probe-" + synchronous + ".db");
  sqlite3* db = nullptr;
  if (sqlite3_open(file.c_str(), &db) != SQLITE_OK) throw std::runtime_error("cannot open " + file.string());
  std::vector<double> samples;
  try {
    sqlite_exec(db, "PRAGMA journal_mode=WAL");
    sqlite_exec(db, "PRAGMA synchronous=" + synchronous);
    sqlite_exec(db, "CREATE TABLE t (id INTEGER PRIMARY KEY, payload TEXT NOT NULL)");
    const std::string payload(300, 'p');
    for (int i = 0; i < n; ++i) {
      samples.push_back(time_ms([&] {
        sqlite_exec(db, "BEGIN IMMEDIATE");
        sqlite_exec(db, "INSERT INTO t (payload) VALUES ('" + payload + "')");
        sqlite_exec(db, "COMMIT");
      }));
    }
  } catch (...) {
    sqlite3_close(db);
    throw;
  }
  sqlite3_close(db);
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(file.string() + suffix);
  return summarize(samples);
}

Summary probe_jobstore_submit(const fs::path& dir, const std::string& scenario_json, int n) {
  const fs::path file = dir / "probe-jobstore.db";
  std::vector<double> samples;
  {
    store::JobStore store(file.string());
    int64_t now = 1'700'000'000'000;
    for (int i = 0; i < n; ++i)
      samples.push_back(time_ms([&] { store.submit("", "lumped", scenario_json, 0, 3, ++now); }));
  }
  for (const char* suffix : {"", "-wal", "-shm"}) fs::remove(file.string() + suffix);
  return summarize(samples);
}

SceneProbe probe_scene(const std::string& scenario_json, const fs::path& out_dir, int reps) {
  SceneProbe probe;
  std::vector<double> validate, run, h5, json, csv, all;
  NoControl control;
  for (int i = 0; i < reps; ++i) {
    config::Scenario scenario;
    validate.push_back(
        time_ms([&] { scenario = bridge::validate(bridge::scenario_proto_from_json_text(scenario_json)); }));
    run.push_back(time_ms([&] { probe.result = scene::run(scenario, control); }));
    const io::Provenance provenance{config::to_json(scenario).dump(), "j-bench"};
    const fs::path scratch = out_dir / ("rep-" + std::to_string(i));
    fs::create_directories(scratch);
    h5.push_back(time_ms([&] { io::write_result_h5(scratch / "result.h5", probe.result, provenance); }));
    json.push_back(time_ms([&] { io::write_metrics_json(scratch / "metrics.json", probe.result); }));
    csv.push_back(time_ms([&] { io::write_pv_loop_csv(scratch / "pv_loop.csv", probe.result); }));
    fs::remove_all(scratch);
    const fs::path dir = out_dir / "job";
    std::vector<fs::path> files;
    all.push_back(time_ms([&] { files = io::write_results(dir, probe.result, provenance); }));
    probe.files = files;
  }
  for (const auto& f : probe.files) probe.file_bytes[f.filename().string()] = static_cast<int64_t>(fs::file_size(f));
  probe.complete_request_bytes = worker::to_proto(probe.result).ByteSizeLong();
  probe.validate_ms = summarize(validate);
  probe.run_ms = summarize(run);
  probe.write_h5_ms = summarize(h5);
  probe.write_json_ms = summarize(json);
  probe.write_csv_ms = summarize(csv);
  probe.write_all_ms = summarize(all);
  return probe;
}

Summary probe_mpirun(int ranks, int reps) {
  const std::string command =
      "mpirun -np " + std::to_string(ranks) + " --oversubscribe --bind-to none /bin/true > /dev/null 2>&1";
  std::vector<double> samples;
  for (int i = 0; i < reps; ++i) samples.push_back(time_ms([&] { (void)std::system(command.c_str()); }));
  return summarize(samples);
}

}  // namespace systole::bench
