#include "solver/lumped/simulate.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <sstream>
#include <string>

#include "solver/diagnostics/beat_metrics.h"

namespace systole::lumped {
namespace {

// The curves of one beat at every integrator step, start and end included.
struct BeatCurves {
  std::vector<double> time_s, lv_volume_ml, lv_pressure_mmhg, la_volume_ml, la_pressure_mmhg,
      aortic_pressure_mmhg, mitral_flow_ml_s, aortic_flow_ml_s;
  void clear() {
    for (auto* v : all()) v->clear();
  }
  void push(double t_s, const Readout& r) {
    time_s.push_back(t_s);
    lv_volume_ml.push_back(r.lv_volume_ml);
    lv_pressure_mmhg.push_back(r.lv_pressure_mmhg);
    la_volume_ml.push_back(r.la_volume_ml);
    la_pressure_mmhg.push_back(r.la_pressure_mmhg);
    aortic_pressure_mmhg.push_back(r.aortic_pressure_mmhg);
    mitral_flow_ml_s.push_back(r.mitral_flow_ml_s);
    aortic_flow_ml_s.push_back(r.aortic_flow_ml_s);
  }
  std::array<std::vector<double>*, 8> all() {
    return {&time_s,           &lv_volume_ml,         &lv_pressure_mmhg, &la_volume_ml,
            &la_pressure_mmhg, &aortic_pressure_mmhg, &mitral_flow_ml_s, &aortic_flow_ml_s};
  }
};

// Output series, in RunResult order.
constexpr int kSeries = 8;
using Row = std::array<double, kSeries>;
const std::array<std::pair<const char*, const char*>, kSeries> kSeriesNames{{
    {"time_s", "s"},
    {"lv_pressure_mmhg", "mmHg"},
    {"lv_volume_ml", "ml"},
    {"la_pressure_mmhg", "mmHg"},
    {"la_volume_ml", "ml"},
    {"aortic_pressure_mmhg", "mmHg"},
    {"mitral_flow_ml_s", "ml/s"},
    {"aortic_flow_ml_s", "ml/s"},
}};

// Samples the beat every interval_s from its start (end excluded), linear in time between steps.
std::vector<Row> sample_beat(const BeatCurves& c, double beat_start_s, double period_s,
                             double interval_s) {
  std::vector<Row> rows;
  const auto& t = c.time_s;
  size_t i = 1;
  for (int j = 0;; ++j) {
    const double ts = beat_start_s + j * interval_s;
    if (ts >= beat_start_s + period_s * (1 - 1e-12)) break;
    while (i + 1 < t.size() && t[i] < ts) ++i;
    const double w = std::clamp((ts - t[i - 1]) / (t[i] - t[i - 1]), 0.0, 1.0);
    auto lerp = [&](const std::vector<double>& v) { return v[i - 1] + w * (v[i] - v[i - 1]); };
    rows.push_back({ts, lerp(c.lv_pressure_mmhg), lerp(c.lv_volume_ml), lerp(c.la_pressure_mmhg),
                    lerp(c.la_volume_ml), lerp(c.aortic_pressure_mmhg), lerp(c.mitral_flow_ml_s),
                    lerp(c.aortic_flow_ml_s)});
  }
  return rows;
}

}  // namespace

std::vector<double> beat_step_grid_s(const Circulation& circulation, double max_dt_s) {
  const double period = circulation.period_s();
  std::vector<double> knots{0.0, period};
  for (double b : circulation.activation_breakpoints_s())
    if (b > 0 && b < period) knots.push_back(b);
  std::sort(knots.begin(), knots.end());
  std::vector<double> grid{0.0};
  for (size_t k = 1; k < knots.size(); ++k) {
    const double a = grid.back(), b = knots[k];
    if (b - a <= 1e-9 * period) continue;  // coincident breakpoints
    const int n = std::max(1, static_cast<int>(std::ceil((b - a) / max_dt_s - 1e-9)));
    for (int i = 1; i <= n; ++i) grid.push_back(i == n ? b : a + (b - a) * i / n);
  }
  grid.back() = period;
  return grid;
}

RunResult simulate(const config::Scenario& s,
                   const std::function<void(const ProgressReport&)>& on_beat,
                   const std::function<bool()>& cancel_requested) {
  Circulation circulation(s);
  const double period = circulation.period_s();
  const std::vector<double> grid = beat_step_grid_s(circulation, s.lumped.time_step_ms * 1e-3);
  const size_t keep_beats = static_cast<size_t>(s.outputs.time_series_last_beats);

  RunResult result;
  BeatCurves curves;
  std::deque<std::vector<Row>> kept;  // sampled series of the latest beats
  std::map<std::string, double> last;
  double previous_edv = circulation.readout().lv_volume_ml;
  double relative_change = 0;
  int beats_done = 0;
  bool periodic = false, cancelled = false;

  for (int beat = 1; beat <= s.beats; ++beat) {
    if (cancel_requested && cancel_requested()) {
      cancelled = true;
      break;
    }
    // --- one beat: t0 is the LV activation onset -----------------------------------------
    const double t0 = (beat - 1) * period;
    curves.clear();
    curves.push(t0, circulation.readout());
    for (size_t i = 1; i < grid.size(); ++i) {
      circulation.advance(grid[i] - grid[i - 1]);
      curves.push(t0 + grid[i], circulation.readout());
    }
    // --- metrics of this beat --------------------------------------------------------------
    diagnostics::BeatSamples samples{curves.time_s,
                                     curves.lv_volume_ml,
                                     curves.lv_pressure_mmhg,
                                     curves.aortic_pressure_mmhg,
                                     curves.mitral_flow_ml_s,
                                     curves.aortic_flow_ml_s,
                                     t0,
                                     period};
    last = diagnostics::to_map(diagnostics::compute_beat_metrics(samples));
    const double edv = last.at("edv_ml");
    relative_change = std::abs(edv - previous_edv) / previous_edv;
    previous_edv = edv;
    last["beat"] = beat;
    last["beat_start_s"] = t0;
    last["edv_relative_change"] = relative_change;
    if (s.outputs.metrics) result.beats.push_back(last);
    if (s.outputs.time_series) {
      kept.push_back(sample_beat(curves, t0, period, s.outputs.time_series_interval_ms * 1e-3));
      if (keep_beats > 0 && kept.size() > keep_beats) kept.pop_front();
    }
    beats_done = beat;
    if (on_beat) {
      ProgressReport report;
      report.simulated_time_s = t0 + period;
      report.beat = beat;
      report.beats_total = s.beats;
      report.fraction = static_cast<double>(beat) / s.beats;
      std::ostringstream m;
      m << "beat " << beat << ": EF " << last.at("ejection_fraction_percent") << " %, EDV " << edv
        << " ml, |dEDV|/EDV " << relative_change;
      report.message = m.str();
      report.latest_beat_metrics = last;
      on_beat(report);
    }
    if (s.periodicity_tolerance > 0 && beat >= 2 && relative_change < s.periodicity_tolerance) {
      periodic = true;
      break;
    }
  }

  // --- summary -------------------------------------------------------------------------------
  result.metrics = last;
  result.metrics.erase("beat");
  result.metrics.erase("beat_start_s");
  result.metrics["heart_rate_bpm"] = s.heart_rate_bpm;
  result.metrics["beats_simulated"] = beats_done;
  result.metrics["periodic"] = periodic ? 1 : 0;
  result.metrics["edv_relative_change"] = relative_change;
  result.metrics["cancelled"] = cancelled ? 1 : 0;
  std::ostringstream note;
  if (cancelled)
    note << "cancelled before beat " << beats_done + 1;
  else if (periodic)
    note << "periodic state reached at beat " << beats_done << " (|dEDV|/EDV = " << relative_change
         << " < " << s.periodicity_tolerance << ")";
  else
    note << "no periodic state after " << beats_done << " beats (|dEDV|/EDV = " << relative_change
         << ")";
  result.notes.push_back(note.str());

  if (s.outputs.time_series) {
    for (const auto& [name, unit] : kSeriesNames) result.series.push_back({name, unit, {}});
    for (const auto& rows : kept)
      for (const Row& row : rows)
        for (int k = 0; k < kSeries; ++k) result.series[k].values.push_back(row[k]);
  }
  return result;
}

}  // namespace systole::lumped
