#pragma once
// What a scene returns: plain data, written by solver/io and sent back by the worker.
#include <map>
#include <string>
#include <vector>

namespace systole {

// One sampled curve; all series of a RunResult share the sampling of the first ("time_s").
struct Series {
  std::string name;  // with its unit in the name: "lv_pressure_mmhg"
  std::string unit;  // "mmHg"
  std::vector<double> values;
};

struct RunResult {
  // Summary metrics (metrics.json): the last simulated beat plus run facts, e.g.
  // ejection_fraction_percent, cardiac_output_l_min, beats_simulated, wall_time_s.
  std::map<std::string, double> metrics;
  // Per-beat metrics, beats[i] is beat i+1.
  std::vector<std::map<std::string, double>> beats;
  // Time series, series[0] is "time_s".
  std::vector<Series> series;
  // Phase averages over the whole beats after the first (the seed's statistics; scenes fsi/fsei,
  // solver/diagnostics/phase_average.h): [0] is "phase" (t/T at the bins' centres), then for
  // every series X but time_s, X (the mean over the beats) and X_rms (the root mean square of the
  // beats' deviation from it). Empty with fewer than two whole beats.
  std::vector<Series> phase_averaged;
  // Free-form facts worth recording (e.g. "periodic state reached at beat 12").
  std::vector<std::string> notes;
};

// What a running scene reports; see scene::RunControl.
struct ProgressReport {
  double simulated_time_s = 0;
  int beat = 0;         // beat in progress, 1-based
  int beats_total = 0;  // most beats the run may take
  double fraction = 0;  // 0..1
  std::string message;
  std::map<std::string, double> latest_beat_metrics;
};

}  // namespace systole
