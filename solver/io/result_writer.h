#pragma once
// Results of one job: result.h5 (time series with units as attributes, per-beat metrics,
// summary metrics, the scenario JSON and the solver version/revision as provenance; chunked,
// shuffle + gzip), metrics.json, time_series.csv and pv_loop.csv beside it. docs/results.md describes the layout.
#include <filesystem>
#include <string>
#include <vector>

#include "solver/core/run_result.h"

namespace systole::io {

struct Provenance {
  std::string scenario_json;  // the complete scenario, defaults expanded (config::to_json)
  std::string job_id;         // "" for local runs (systole-solve)
};

// Writes result.h5 and metrics.json into `dir` (created if missing), time_series.csv when the
// result has time series, phase_averaged.csv when it has phase averages, pv_loop.csv when it has the LV pressure and volume series, and
// returns the paths written. Each file is written to a temporary name and renamed, so a reader never sees
// a half-written file. Throws std::runtime_error on I/O failure.
std::vector<std::filesystem::path> write_results(const std::filesystem::path& dir,
                                                 const RunResult& result,
                                                 const Provenance& provenance);

void write_result_h5(const std::filesystem::path& file, const RunResult& result,
                     const Provenance& provenance);
void write_metrics_json(const std::filesystem::path& file, const RunResult& result);
// LV pressure-volume loop of the sampled beats: columns time_s, lv_volume_ml, lv_pressure_mmhg.
// Throws std::logic_error when has_pv_loop(result) is false.
bool has_pv_loop(const RunResult& result);
void write_pv_loop_csv(const std::filesystem::path& file, const RunResult& result);
// Every series as a column (header = series names, units in the names), one row per sample.
// Series whose length differs from the first one's are left out (they stay in result.h5).
void write_time_series_csv(const std::filesystem::path& file, const RunResult& result);

// Reads back what write_result_h5 wrote (tests, tools).
struct H5Contents {
  std::vector<Series> series;
  std::vector<Series> phase_averaged;  // empty when the file has none
  std::map<std::string, std::vector<double>> beats;
  std::map<std::string, double> metrics;
  std::string scenario_json, version, git_revision;
};
H5Contents read_result_h5(const std::filesystem::path& file);

// Unit of a quantity from its name's suffix ("_mmhg" → "mmHg"); "" if nondimensional.
std::string unit_from_name(const std::string& name);

}  // namespace systole::io
