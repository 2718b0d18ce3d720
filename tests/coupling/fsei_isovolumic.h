#pragma once
// The isovolumic contraction of scenes fsi/fsei from a run's 1-ms series (from t = 0): the checks
// the two scenes' first-milliseconds tests share (fsei_scene_test.cc, fsei_ep_scene_test.cc).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/scene/fsei_scene.h"

namespace systole::scene {

struct IsovolumicWindow {
  double through_aortic_ml = 0, through_mitral_ml = 0;  // over the window, + into the aorta / the LV
  double lv_start_mmhg = 0, lv_end_mmhg = 0, lv_mean_mmhg = 0;
  double lv_leak_ml = 0;                // what the LV lost beyond its orifices over the window
  double leak_ml_s_per_mmhg = 0;        // lv_leak_ml per second per mmHg of the LV's mean pressure
};

// Asserts what holds at any setting that contracts behind closed valves: every metric finite,
// every interval converged, one sample per ms to `to_ms`; the valves held shut by their pressure
// differences (root above LV from `from_ms`, after the aorta's ramp; LV above LA from 25 ms); the
// LV pressure rising at every sample over the one 5 ms before from 25 ms. Returns the window
// [from_ms, to_ms]'s flows, pressures and leak (printed as [measured]) for the caller's bounds.
inline IsovolumicWindow check_isovolumic_contraction(const RunResult& r, double from_ms, double to_ms) {
  auto series = [&](const std::string& name) -> const std::vector<double>& {
    for (const auto& x : r.series)
      if (x.name == name) return x.values;
    ADD_FAILURE() << "no series " << name;
    return r.series.front().values;
  };
  const auto& t = series("time_s");
  const auto& p_lv = series("lv_pressure_mmhg");
  const auto& p_la = series("la_pressure_mmhg");
  const auto& p_ao = series("aortic_root_pressure_mmhg");
  const auto& v_lv = series("lv_volume_ml");
  const auto& q_ao = series("aortic_flow_ml_s");
  const auto& q_mi = series("mitral_flow_ml_s");
  auto at = [&](double ms) { return static_cast<std::size_t>(std::lround(ms)); };  // 1-ms samples from 0
  IsovolumicWindow w;
  EXPECT_EQ(t.size(), at(to_ms) + 1);
  if (t.size() != at(to_ms) + 1) return w;
  for (const auto& [key, value] : r.metrics) EXPECT_TRUE(std::isfinite(value)) << key;
  EXPECT_EQ(r.metrics.at("coupling_unconverged_intervals"), 0.0);
  const double span_s = 1e-3 * (to_ms - from_ms);
  for (std::size_t i = at(from_ms); i < at(to_ms); ++i) {
    w.through_aortic_ml += 0.5e-3 * (q_ao[i] + q_ao[i + 1]);
    w.through_mitral_ml += 0.5e-3 * (q_mi[i] + q_mi[i + 1]);
    w.lv_mean_mmhg += 0.5 * (p_lv[i] + p_lv[i + 1]) / (to_ms - from_ms);
  }
  w.lv_start_mmhg = p_lv[at(from_ms)];
  w.lv_end_mmhg = p_lv[at(to_ms)];
  w.lv_leak_ml = (w.through_mitral_ml - w.through_aortic_ml) - (v_lv[at(to_ms)] - v_lv[at(from_ms)]);
  w.leak_ml_s_per_mmhg = w.lv_leak_ml / span_s / w.lv_mean_mmhg;
  std::printf("  [measured] %g-%g ms: aortic %.3f ml, mitral %.3f ml; LV %.2f -> %.2f mmHg, %.3f -> %.3f ml; "
              "root %.1f mmHg; LV leak %.3f ml at %.2f mmHg mean: %.3f ml/s per mmHg\n",
              from_ms, to_ms, w.through_aortic_ml, w.through_mitral_ml, w.lv_start_mmhg, w.lv_end_mmhg, v_lv[at(from_ms)],
              v_lv[at(to_ms)], p_ao[at(to_ms)], w.lv_leak_ml, w.lv_mean_mmhg, w.leak_ml_s_per_mmhg);
  for (std::size_t i = at(from_ms); i < t.size(); ++i) EXPECT_GT(p_ao[i], p_lv[i]) << "aortic valve, " << t[i] << " s";
  for (std::size_t i = at(25); i < t.size(); ++i) EXPECT_GT(p_lv[i], p_la[i]) << "mitral valve, " << t[i] << " s";
  for (std::size_t i = at(25); i < t.size(); ++i) EXPECT_GT(p_lv[i], p_lv[i - 5]) << t[i];
  return w;
}

}  // namespace systole::scene
