#include "solver/diagnostics/beat_metrics.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

namespace systole::diagnostics {
namespace {

// Messages are built only on failure: these checks run over every sample of every beat.
[[noreturn]] void fail(const std::string& what) {
  throw std::invalid_argument("diagnostics: " + what);
}

void require(bool ok, const char* what) {
  if (!ok) fail(what);
}

void check_time(std::span<const double> time_s) {
  if (time_s.size() < 2)
    fail("a beat needs at least 2 samples, got " + std::to_string(time_s.size()));
  for (size_t i = 1; i < time_s.size(); ++i)
    if (!(time_s[i] > time_s[i - 1]))
      fail("time_s must be strictly increasing (sample " + std::to_string(i) + ")");
}

void check_same_size(std::span<const double> time_s, std::span<const double> v, const char* name) {
  if (v.size() != time_s.size())
    fail(std::string(name) + " has " + std::to_string(v.size()) + " samples, time_s has " +
         std::to_string(time_s.size()));
}

double peak_abs(std::span<const double> v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// The topographic prominence of the local maximum q[i] within q[first..]: its height above the
// higher of the two lowest points between it and the nearest higher sample on either side (or the
// range's ends). A ripple on the rise of a wave has a small prominence; the wave's crest a large
// one (ours: a coupled run's 39-ml/s ripple on its E wave's rise;
// BeatMetrics.ARippleOnTheEWavesRiseIsNotTheEWave).
double prominence(std::span<const double> q, size_t first, size_t i) {
  double left_min = q[i];
  for (size_t j = i; j-- > first && q[j] <= q[i];) left_min = std::min(left_min, q[j]);
  double right_min = q[i];
  for (size_t j = i + 1; j < q.size() && q[j] <= q[i]; ++j) right_min = std::min(right_min, q[j]);
  return q[i] - std::max(left_min, right_min);
}

}  // namespace

double stroke_volume_ml(double edv_ml, double esv_ml) { return edv_ml - esv_ml; }

double ejection_fraction_percent(double edv_ml, double esv_ml) {
  return edv_ml > 0 ? 100.0 * (edv_ml - esv_ml) / edv_ml : 0.0;
}

double cardiac_output_l_min(double stroke_volume_ml, double heart_rate_bpm) {
  return stroke_volume_ml * heart_rate_bpm / 1000.0;  // ml/beat * beats/min -> l/min
}

double integrate(std::span<const double> time_s, std::span<const double> values) {
  check_time(time_s);
  check_same_size(time_s, values, "values");
  double sum = 0;
  for (size_t i = 1; i < time_s.size(); ++i)
    sum += 0.5 * (values[i] + values[i - 1]) * (time_s[i] - time_s[i - 1]);
  return sum;
}

double time_average(std::span<const double> time_s, std::span<const double> values) {
  return integrate(time_s, values) / (time_s.back() - time_s.front());
}

double value_at(std::span<const double> time_s, std::span<const double> values, double t) {
  check_same_size(time_s, values, "values");
  require(!time_s.empty(), "value_at needs samples");
  if (t <= time_s.front()) return values.front();
  if (t >= time_s.back()) return values.back();
  const size_t i = std::upper_bound(time_s.begin(), time_s.end(), t) - time_s.begin();
  const double w = (t - time_s[i - 1]) / (time_s[i] - time_s[i - 1]);
  return values[i - 1] + w * (values[i] - values[i - 1]);
}

std::optional<double> first_crossing(std::span<const double> time_s, std::span<const double> values,
                                     double level, Crossing direction) {
  return first_lasting_crossing(time_s, values, level, direction, 0.0);  // no dwell: the first crossing
}

std::optional<double> first_lasting_crossing(std::span<const double> time_s, std::span<const double> values,
                                             double level, Crossing direction, double min_dwell_s) {
  check_same_size(time_s, values, "values");
  require(min_dwell_s >= 0, "min_dwell_s must be >= 0");
  const bool up = direction == Crossing::kUpward;
  const auto beyond = [&](double x) { return up ? x > level : x <= level; };
  for (std::size_t i = 1; i < values.size(); ++i) {
    const double a = values[i - 1], b = values[i];
    if (beyond(a) || !beyond(b)) continue;  // no crossing between samples i-1 and i
    const double t = time_s[i - 1] + (level - a) / (b - a) * (time_s[i] - time_s[i - 1]);
    std::size_t j = i;  // samples i, i+1, ... within the dwell must stay beyond the level
    while (j < values.size() && time_s[j] <= t + min_dwell_s && beyond(values[j])) ++j;
    if (j == values.size() || time_s[j] > t + min_dwell_s) return t;
    i = j;  // back across within the dwell: sample j is on the old side; search on from it
  }
  return std::nullopt;
}

ValveEvents valve_events(std::span<const double> time_s, std::span<const double> flow_ml_s,
                         double beat_start_s, double period_s, double threshold_fraction,
                         double min_dwell_fraction) {
  require(period_s > 0, "period_s must be positive");
  require(min_dwell_fraction >= 0 && min_dwell_fraction < 1, "min_dwell_fraction must be in [0, 1)");
  const double level = threshold_fraction * peak_abs(flow_ml_s), dwell_s = min_dwell_fraction * period_s;
  check_same_size(time_s, flow_ml_s, "flow_ml_s");
  if (time_s.empty()) return {};
  // The valve's state is the side of the level it is on, and only a lasting crossing changes it:
  // the first event is a crossing away from the state of the first sample, the other event the
  // first lasting crossing back after it. A ripple through the level from the state the valve is
  // already in is not an event (a coupled run's aortic flow poked above its level for 1 ms at
  // 18 ms and "closed" there; BeatMetrics.AValveThatStartsClosedClosesOnlyAfterItOpened) (ours).
  const bool starts_open = flow_ml_s.front() > level;
  const Crossing first = starts_open ? Crossing::kDownward : Crossing::kUpward;
  const Crossing second = starts_open ? Crossing::kUpward : Crossing::kDownward;
  const std::optional<double> t_first = first_lasting_crossing(time_s, flow_ml_s, level, first, dwell_s);
  std::optional<double> t_second;
  if (t_first) {
    // search on from the sample just before the first event: the pair that holds it crosses the
    // other way, so no crossing before t_first is found
    const std::size_t k = std::upper_bound(time_s.begin(), time_s.end(), *t_first) - time_s.begin() - 1;
    t_second = first_lasting_crossing(time_s.subspan(k), flow_ml_s.subspan(k), level, second, dwell_s);
  }
  const auto phase = [&](const std::optional<double>& t) -> std::optional<double> {
    if (!t) return std::nullopt;
    return (*t - beat_start_s) / period_s;
  };
  ValveEvents e;
  e.open_phase = phase(starts_open ? t_second : t_first);
  e.close_phase = phase(starts_open ? t_first : t_second);
  return e;
}

BeatMetrics compute_beat_metrics(const BeatSamples& b) {
  check_time(b.time_s);
  check_same_size(b.time_s, b.lv_volume_ml, "lv_volume_ml");
  check_same_size(b.time_s, b.lv_pressure_mmhg, "lv_pressure_mmhg");
  check_same_size(b.time_s, b.aortic_pressure_mmhg, "aortic_pressure_mmhg");
  check_same_size(b.time_s, b.mitral_flow_ml_s, "mitral_flow_ml_s");
  check_same_size(b.time_s, b.aortic_flow_ml_s, "aortic_flow_ml_s");
  require(b.period_s > 0, "period_s must be positive");
  auto phase = [&](double t) { return (t - b.beat_start_s) / b.period_s; };

  BeatMetrics m;
  m.heart_rate_bpm = 60.0 / b.period_s;
  m.aortic_valve = valve_events(b.time_s, b.aortic_flow_ml_s, b.beat_start_s, b.period_s,
                                b.valve_threshold_fraction, b.valve_min_dwell_fraction);
  m.mitral_valve = valve_events(b.time_s, b.mitral_flow_ml_s, b.beat_start_s, b.period_s,
                                b.valve_threshold_fraction, b.valve_min_dwell_fraction);
  const auto& v = b.lv_volume_ml;
  auto at_phase_or = [&](const std::optional<double>& ph, size_t fallback, double& volume,
                         double& pressure) {
    if (ph) {
      const double t = b.beat_start_s + *ph * b.period_s;
      volume = value_at(b.time_s, v, t);
      pressure = value_at(b.time_s, b.lv_pressure_mmhg, t);
    } else {
      volume = v[fallback];
      pressure = b.lv_pressure_mmhg[fallback];
    }
  };
  if (b.end_diastole_at_beat_start) {
    m.edv_ml = v.front();
    m.lv_end_diastolic_pressure_mmhg = b.lv_pressure_mmhg.front();
  } else {
    at_phase_or(m.mitral_valve.close_phase, std::max_element(v.begin(), v.end()) - v.begin(),
                m.edv_ml, m.lv_end_diastolic_pressure_mmhg);
  }
  at_phase_or(m.aortic_valve.close_phase, std::min_element(v.begin(), v.end()) - v.begin(),
              m.esv_ml, m.lv_end_systolic_pressure_mmhg);
  m.stroke_volume_ml = stroke_volume_ml(m.edv_ml, m.esv_ml);
  m.ejection_fraction_percent = ejection_fraction_percent(m.edv_ml, m.esv_ml);
  m.cardiac_output_l_min = cardiac_output_l_min(m.stroke_volume_ml, m.heart_rate_bpm);
  m.aortic_forward_volume_ml = integrate(b.time_s, b.aortic_flow_ml_s);
  m.mitral_inflow_volume_ml = integrate(b.time_s, b.mitral_flow_ml_s);

  const auto& p = b.lv_pressure_mmhg;
  const size_t i_pk = std::max_element(p.begin(), p.end()) - p.begin();
  m.lv_peak_pressure_mmhg = p[i_pk];
  m.lv_peak_pressure_phase = phase(b.time_s[i_pk]);
  const auto& pa = b.aortic_pressure_mmhg;
  m.aortic_pressure_max_mmhg = *std::max_element(pa.begin(), pa.end());
  m.aortic_pressure_min_mmhg = *std::min_element(pa.begin(), pa.end());
  m.aortic_pressure_mean_mmhg = time_average(b.time_s, pa);
  m.mitral_peak_flow_ml_s = *std::max_element(b.mitral_flow_ml_s.begin(), b.mitral_flow_ml_s.end());
  m.aortic_peak_flow_ml_s = *std::max_element(b.aortic_flow_ml_s.begin(), b.aortic_flow_ml_s.end());

  // E and A waves: local maxima of the mitral flow after the mitral valve opens.
  if (m.mitral_valve.open_phase) {
    const double t_open = b.beat_start_s + *m.mitral_valve.open_phase * b.period_s;
    const auto& q = b.mitral_flow_ml_s;
    const double floor = 0.1 * m.mitral_peak_flow_ml_s;
    size_t i_open = 0;
    while (i_open < q.size() && b.time_s[i_open] < t_open) ++i_open;
    std::vector<size_t> peaks;
    for (size_t i = std::max<size_t>(i_open, 1); i + 1 < q.size(); ++i) {
      if (q[i] > floor && q[i] >= q[i - 1] && q[i] > q[i + 1] &&
          prominence(q, i_open, i) >= floor)
        peaks.push_back(i);
    }
    if (!peaks.empty()) {
      m.mitral_e_peak_phase = phase(b.time_s[peaks.front()]);
      m.mitral_e_peak_flow_ml_s = q[peaks.front()];
      if (peaks.size() >= 2) {
        // the largest later maximum, not the last: a 3-D flow ripples after the A wave
        // (w2: 93 ml/s at 0.98 T after its A wave of 328 ml/s at 0.94 T) (ours)
        const size_t a = *std::max_element(peaks.begin() + 1, peaks.end(),
                                           [&](size_t i, size_t j) { return q[i] < q[j]; });
        m.mitral_a_peak_phase = phase(b.time_s[a]);
        m.mitral_a_peak_flow_ml_s = q[a];
      }
    }
  }
  return m;
}

std::map<std::string, double> to_map(const BeatMetrics& m) {
  std::map<std::string, double> out{
      {"heart_rate_bpm", m.heart_rate_bpm},
      {"edv_ml", m.edv_ml},
      {"esv_ml", m.esv_ml},
      {"stroke_volume_ml", m.stroke_volume_ml},
      {"ejection_fraction_percent", m.ejection_fraction_percent},
      {"cardiac_output_l_min", m.cardiac_output_l_min},
      {"aortic_forward_volume_ml", m.aortic_forward_volume_ml},
      {"mitral_inflow_volume_ml", m.mitral_inflow_volume_ml},
      {"lv_end_diastolic_pressure_mmhg", m.lv_end_diastolic_pressure_mmhg},
      {"lv_end_systolic_pressure_mmhg", m.lv_end_systolic_pressure_mmhg},
      {"lv_peak_pressure_mmhg", m.lv_peak_pressure_mmhg},
      {"lv_peak_pressure_phase", m.lv_peak_pressure_phase},
      {"aortic_pressure_max_mmhg", m.aortic_pressure_max_mmhg},
      {"aortic_pressure_min_mmhg", m.aortic_pressure_min_mmhg},
      {"aortic_pressure_mean_mmhg", m.aortic_pressure_mean_mmhg},
      {"mitral_peak_flow_ml_s", m.mitral_peak_flow_ml_s},
      {"aortic_peak_flow_ml_s", m.aortic_peak_flow_ml_s},
  };
  auto put = [&](const char* key, const std::optional<double>& v) {
    if (v) out[key] = *v;
  };
  put("aortic_valve_open_phase", m.aortic_valve.open_phase);
  put("aortic_valve_close_phase", m.aortic_valve.close_phase);
  put("mitral_valve_open_phase", m.mitral_valve.open_phase);
  put("mitral_valve_close_phase", m.mitral_valve.close_phase);
  put("mitral_e_peak_phase", m.mitral_e_peak_phase);
  put("mitral_e_peak_flow_ml_s", m.mitral_e_peak_flow_ml_s);
  put("mitral_a_peak_phase", m.mitral_a_peak_phase);
  put("mitral_a_peak_flow_ml_s", m.mitral_a_peak_flow_ml_s);
  if (m.mitral_e_peak_flow_ml_s && m.mitral_a_peak_flow_ml_s && *m.mitral_a_peak_flow_ml_s > 0)
    out["mitral_e_to_a_ratio"] = *m.mitral_e_peak_flow_ml_s / *m.mitral_a_peak_flow_ml_s;
  return out;
}

}  // namespace systole::diagnostics
