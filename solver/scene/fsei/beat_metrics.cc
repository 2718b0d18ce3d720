// Per-beat metrics of the coupled scene (fsei_scene.h: fsei_beat_metrics).
#include <algorithm>
#include <cmath>
#include <span>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/diagnostics/beat_metrics.h"
#include "solver/scene/fsei_scene.h"

namespace systole::scene {
namespace {

using Metrics = std::map<std::string, double>;

// One whole beat's samples [i0, i0 + n) of the run's series; a window of a series is checked
// finite (InstabilityError of `scene` naming the beat, the series and the time).
struct BeatWindow {
  const std::vector<Series>& series;
  const std::string& scene;
  int beat;
  double start_s, stop_s, period_s;
  std::size_t i0, n;

  const std::vector<double>& find(const std::string& name) const {
    for (const Series& x : series)
      if (x.name == name) return x.values;
    throw std::invalid_argument("fsei_beat_metrics: no series '" + name + "'");
  }
  bool has(const std::string& name) const {
    for (const Series& x : series)
      if (x.name == name) return true;
    return false;
  }
  std::span<const double> operator()(const std::string& name) const {
    const std::span<const double> w(find(name).data() + i0, n);
    for (std::size_t i = 0; i < n; ++i)
      if (!std::isfinite(w[i]))
        throw InstabilityError(scene, "beat " + std::to_string(beat) + " series " + name, find("time_s")[i0 + i],
                               "a non-finite sample");
    return w;
  }
};

// Each beat's peaks of the series that have no 0-D definition (ours).
void peak_metrics(const BeatWindow& w, Metrics& m) {
  struct Peak {
    const char* series;
    const char* metric;
    enum { kLargest, kSmallest, kLargestMagnitude } kind;
  };
  static const Peak peaks[] = {{"kinetic_energy_mj", "kinetic_energy_max_mj", Peak::kLargest},
                               {"lv_twist_deg", "lv_twist_peak_deg", Peak::kLargestMagnitude},
                               {"lv_longitudinal_strain", "lv_longitudinal_strain_min", Peak::kSmallest},
                               {"lv_circumferential_strain", "lv_circumferential_strain_min", Peak::kSmallest},
                               {"mitral_tip_velocity_m_s", "mitral_tip_velocity_max_m_s", Peak::kLargest},
                               {"aortic_tip_velocity_m_s", "aortic_tip_velocity_max_m_s", Peak::kLargest},
                               {"aortic_cusps_wss_max_pa", "aortic_cusps_wss_max_pa", Peak::kLargest},
                               {"la_volume_ml", "la_volume_max_ml", Peak::kLargest},
                               {"la_volume_ml", "la_volume_min_ml", Peak::kSmallest},
                               {"la_pressure_mmhg", "la_pressure_max_mmhg", Peak::kLargest}};
  // the chambers' kinetic energy (not in the series of older runs): its peak where the series is there
  if (w.has("heart_kinetic_energy_mj")) {
    const std::span<const double> v = w("heart_kinetic_energy_mj");
    m["heart_kinetic_energy_max_mj"] = *std::max_element(v.begin(), v.end());
  }
  for (const Peak& p : peaks) {
    const std::span<const double> v = w(p.series);
    double best = v[0];
    for (double x : v)
      if (p.kind == Peak::kLargest ? x > best : p.kind == Peak::kSmallest ? x < best : std::abs(x) > std::abs(best))
        best = x;
    m[p.metric] = best;
  }
}

// The seed's twist is read at end-systole (MODEL.md §8: ≈ 17°): the twist at the aortic closure,
// where the beat has one. The aortic flow's reversal after its peak (ours): where the valve's
// threshold reading (5 % of the peak flow, held for 2 % of the period) takes a slow tail of the
// ejection for the closure, the reversal is the ejection's end (0.347-0.348 T on three grids where
// the threshold read 0.308-0.341 T; docs/notes/fsei-notebook.md).
void end_of_ejection(const BeatWindow& w, const diagnostics::BeatSamples& bs, Metrics& m) {
  if (const auto close = m.find("aortic_valve_close_phase"); close != m.end())
    m["lv_twist_end_systole_deg"] =
        diagnostics::value_at(bs.time_s, w("lv_twist_deg"), w.start_s + close->second * w.period_s);
  const std::span<const double> q = bs.aortic_flow_ml_s;
  const std::size_t i_peak = std::max_element(q.begin(), q.end()) - q.begin();
  if (const auto t_rev = diagnostics::first_crossing(bs.time_s.subspan(i_peak), q.subspan(i_peak), 0.0,
                                                     diagnostics::Crossing::kDownward))
    m["aortic_flow_reversal_phase"] = (*t_rev - w.start_s) / w.period_s;
}

// An open valve as a clinician reads it (ours, after the Gorlin and Hakki formulas with a
// discharge coefficient of 1): the mean gradient across it (upstream − downstream chamber) and the
// effective orifice area A = Q̄ / sqrt(2 Δp̄ / ρ) over its open interval (its opening to its
// closure, or to the beat's end). Healthy adults: mitral 4-6 cm² at a mean gradient < 2 mmHg, a
// severe stenosis < 1 cm²; aortic 3-4 cm², a severe stenosis < 1 cm² or a mean gradient > 40 mmHg
// (Baumgartner et al., J Am Soc Echocardiogr 22:1-23, 2009). A closure before the opening is the
// previous beat's flow ending (the mitral's A wave): the interval then runs to the beat's end. The
// area is left out when the valve did not open or the mean gradient or flow is not positive.
void open_valve_metrics(const BeatWindow& w, std::span<const double> time_s, const std::string& valve,
                        std::span<const double> flow, std::span<const double> upstream,
                        std::span<const double> downstream, double blood_density_kg_per_m3, Metrics& m) {
  const auto open = m.find(valve + "_valve_open_phase");
  if (open == m.end()) return;
  const double t_open = w.start_s + open->second * w.period_s;
  const auto close = m.find(valve + "_valve_close_phase");
  const double t_close =
      close != m.end() && close->second > open->second ? w.start_s + close->second * w.period_s : w.stop_s;
  if (!(t_close > t_open)) return;
  std::vector<double> t, q, dp;  // the open interval, its ends interpolated
  auto push = [&](double at) {
    t.push_back(at);
    q.push_back(diagnostics::value_at(time_s, flow, at));
    dp.push_back(diagnostics::value_at(time_s, upstream, at) - diagnostics::value_at(time_s, downstream, at));
  };
  push(t_open);
  for (std::size_t i = 0; i < w.n; ++i)
    if (time_s[i] > t_open && time_s[i] < t_close) {
      t.push_back(time_s[i]);
      q.push_back(flow[i]);
      dp.push_back(upstream[i] - downstream[i]);
    }
  push(t_close);
  const double q_mean_ml_s = diagnostics::time_average(t, q), dp_mean_mmhg = diagnostics::time_average(t, dp);
  m[valve + "_mean_gradient_mmhg"] = dp_mean_mmhg;
  if (dp_mean_mmhg > 0 && q_mean_ml_s > 0) {
    const double speed_m_s = std::sqrt(2 * dp_mean_mmhg * units::kPaPerMmHg / blood_density_kg_per_m3);
    m[valve + "_effective_orifice_area_cm2"] = q_mean_ml_s / (100 * speed_m_s);  // ml/s / (cm/s)
  }
}

// The 0-D scene's definitions (solver/diagnostics/beat_metrics.h) on the beat's window, then the
// coupled scene's own.
Metrics one_beat(const BeatWindow& w, double blood_density_kg_per_m3) {
  diagnostics::BeatSamples bs;
  bs.time_s = w("time_s");
  bs.lv_volume_ml = w("lv_volume_ml");
  bs.lv_pressure_mmhg = w("lv_pressure_mmhg");
  bs.aortic_pressure_mmhg = w("aortic_root_pressure_mmhg");
  bs.mitral_flow_ml_s = w("mitral_flow_ml_s");
  bs.aortic_flow_ml_s = w("aortic_flow_ml_s");
  bs.beat_start_s = w.start_s;
  bs.period_s = w.period_s;
  // a valve is open while its flow exceeds 5 % of its peak: the leaflets' motion and the closed
  // valves' leak move a few % of the peak flow back and forth (ours) ...
  bs.valve_threshold_fraction = 0.05;
  // ... and the flow must stay across that level for 2 % of the period (17 ms at 70 bpm): the
  // leaflets' flutter moves the flow through it for a few ms around an opening (ours)
  bs.valve_min_dwell_fraction = 0.02;
  // End-diastole is the window's start (ours): the scene starts every beat at the activation with
  // the valves closed (MODEL.md §1), not at the first mitral closure in the window (which, after a
  // weak E wave, is a closure of a closed valve's back-and-forth flow: EF −5 % for the first
  // ejecting run; docs/notes/fsei-notebook.md).
  bs.end_diastole_at_beat_start = true;
  Metrics m = diagnostics::to_map(diagnostics::compute_beat_metrics(bs));
  peak_metrics(w, m);
  end_of_ejection(w, bs, m);
  open_valve_metrics(w, bs.time_s, "mitral", bs.mitral_flow_ml_s, w("la_pressure_mmhg"), bs.lv_pressure_mmhg,
                     blood_density_kg_per_m3, m);
  open_valve_metrics(w, bs.time_s, "aortic", bs.aortic_flow_ml_s, bs.lv_pressure_mmhg, bs.aortic_pressure_mmhg,
                     blood_density_kg_per_m3, m);
  m["beat"] = w.beat;
  m["beat_start_s"] = w.start_s;
  for (const auto& [key, value] : m)
    if (!std::isfinite(value))
      throw InstabilityError(w.scene, "beat " + std::to_string(w.beat) + " metric " + key, w.stop_s,
                             "a non-finite beat metric");
  return m;
}

}  // namespace

std::vector<std::map<std::string, double>> fsei_beat_metrics(const std::vector<Series>& series, double period_ms,
                                                             double blood_density_kg_per_m3, const std::string& scene) {
  if (!(blood_density_kg_per_m3 > 0))
    throw std::invalid_argument("fsei_beat_metrics: blood_density_kg_per_m3 must be > 0, got " +
                                std::to_string(blood_density_kg_per_m3));
  BeatWindow probe{series, scene, 0, 0, 0, 0, 0, 0};
  const std::vector<double>& t_s = probe.find("time_s");
  for (const Series& x : series)
    if (x.values.size() != t_s.size())
      throw std::invalid_argument("fsei_beat_metrics: series '" + x.name + "' has " + std::to_string(x.values.size()) +
                                  " samples, time_s " + std::to_string(t_s.size()));
  std::vector<Metrics> out;
  const double period_s = 1e-3 * period_ms, tol_s = 1e-9;
  if (t_s.empty() || !(period_s > 0)) return out;
  for (int b = 1; b * period_s <= t_s.back() + tol_s; ++b) {
    const double start = (b - 1) * period_s, stop = b * period_s;
    std::size_t i0 = 0;
    while (i0 < t_s.size() && t_s[i0] < start - tol_s) ++i0;
    std::size_t i1 = i0;
    while (i1 < t_s.size() && t_s[i1] <= stop + tol_s) ++i1;
    // only whole beats: samples at both ends
    if (i1 - i0 < 3 || std::abs(t_s[i0] - start) > tol_s || std::abs(t_s[i1 - 1] - stop) > tol_s) continue;
    out.push_back(one_beat({series, scene, b, start, stop, period_s, i0, i1 - i0}, blood_density_kg_per_m3));
  }
  return out;
}

}  // namespace systole::scene
