// Unit tier of the 0-D circulation: healthy ranges of the default scenario, physiological
// trends, conservation, the external-chamber interface, instability detection, cancellation,
// outputs. Ranges are the physiological targets of the brief (docs: solver/lumped/README.md),
// not numbers read off the code.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/lumped/activation.h"
#include "solver/lumped/circulation.h"
#include "solver/lumped/simulate.h"
#include "solver/lumped/valve.h"

namespace systole::lumped {
namespace {

config::Scenario quiet_default() {
  config::Scenario s = config::default_scenario();
  s.outputs.time_series = false;
  return s;
}

// ---- building blocks ---------------------------------------------------------------------

TEST(Activation, RaisedCosineShapeAndTiming) {
  const config::Scenario s = config::default_scenario();
  const ChamberTiming lv = ChamberTiming::lv(s);
  EXPECT_NEAR(activation_duration_scale(60.0 / 70.0), 1.0, 1e-15);
  EXPECT_NEAR(lv.contraction_s, s.lumped.lv.contraction_ms * 1e-3, 1e-15);
  EXPECT_EQ(lv.activation(0.0), 0.0);
  EXPECT_NEAR(lv.activation(lv.contraction_s), 1.0, 1e-12);
  EXPECT_NEAR(lv.activation(0.5 * lv.contraction_s), 0.5, 1e-12);
  EXPECT_NEAR(lv.activation(lv.contraction_s + 0.5 * lv.relaxation_s), 0.5, 1e-12);
  EXPECT_EQ(lv.activation(lv.contraction_s + lv.relaxation_s + 1e-3), 0.0);
  // Periodic, and continuous across the breakpoints.
  EXPECT_NEAR(lv.activation(0.1 + lv.period_s), lv.activation(0.1), 1e-12);
  for (double b : lv.breakpoints_s())
    EXPECT_NEAR(lv.activation(b - 1e-9), lv.activation(b + 1e-9), 1e-6);
  // The LA starts av_delay before the next LV onset.
  const ChamberTiming la = ChamberTiming::la(s);
  EXPECT_NEAR(la.onset_s, la.period_s - s.av_delay_ms * 1e-3, 1e-15);
  EXPECT_EQ(la.activation(la.onset_s - 1e-6), 0.0);
  EXPECT_GT(la.activation(la.onset_s + 1e-3), 0.0);
  // Faster heart, shorter twitch: sqrt(period ratio).
  config::Scenario fast = s;
  fast.heart_rate_bpm = 140;
  EXPECT_NEAR(ChamberTiming::lv(fast).contraction_s / lv.contraction_s, std::sqrt(0.5), 1e-12);
}

TEST(SmoothDiode, LinearWhenClosedAndOpenMonotoneBetween) {
  const SmoothDiode d(0.01, 1000.0);  // open 100 ml/s/mmHg, closed 1e-3
  EXPECT_DOUBLE_EQ(d.flow_ml_s(-50), -0.05);
  EXPECT_DOUBLE_EQ(d.flow_ml_s(2.0), 200.0);
  EXPECT_EQ(d.flow_ml_s(0.0), 0.0);
  double previous = d.flow_ml_s(-1);
  const double w = SmoothDiode::kTransitionWidth_mmhg;
  for (double dp = -1; dp <= 1; dp += 1e-3) {
    const double q = d.flow_ml_s(dp);
    EXPECT_GE(q, previous);
    previous = q;
    // The slope agrees with a centred difference of the flow.
    const double h = 1e-7;
    EXPECT_NEAR(d.conductance_slope(dp), (d.flow_ml_s(dp + h) - d.flow_ml_s(dp - h)) / (2 * h),
                1e-4 * d.open_conductance());
  }
  // Continuous slope at both ends of the transition.
  EXPECT_NEAR(d.conductance_slope(1e-12), d.closed_conductance(), 1e-6);
  EXPECT_NEAR(d.conductance_slope(w - 1e-12), d.open_conductance(), 1e-6);
  EXPECT_THROW(SmoothDiode(0.0, 1.0), std::invalid_argument);
}

// ---- the healthy default -----------------------------------------------------------------

TEST(LumpedHealthy, DefaultScenarioIsAHealthyPeriodicLeftHeart) {
  const config::Scenario s = config::default_scenario();
  const RunResult r = simulate(s);
  const auto& m = r.metrics;
  EXPECT_NEAR(m.at("edv_ml"), 125.0, 0.03 * 125.0);
  EXPECT_GE(m.at("ejection_fraction_percent"), 55.0);
  EXPECT_LE(m.at("ejection_fraction_percent"), 62.0);
  EXPECT_GE(m.at("cardiac_output_l_min"), 4.8);
  EXPECT_LE(m.at("cardiac_output_l_min"), 5.4);
  EXPECT_GE(m.at("lv_peak_pressure_mmhg"), 110.0);
  EXPECT_LE(m.at("lv_peak_pressure_mmhg"), 130.0);
  EXPECT_GE(m.at("aortic_pressure_max_mmhg"), 110.0);
  EXPECT_LE(m.at("aortic_pressure_max_mmhg"), 130.0);
  EXPECT_GE(m.at("aortic_pressure_min_mmhg"), 70.0);
  EXPECT_LE(m.at("aortic_pressure_min_mmhg"), 90.0);
  // Consistency of the summary: SV = EDV - ESV, CO = SV * HR.
  EXPECT_NEAR(m.at("stroke_volume_ml"), m.at("edv_ml") - m.at("esv_ml"), 1e-9);
  EXPECT_NEAR(m.at("cardiac_output_l_min"), m.at("stroke_volume_ml") * 70.0 / 1000.0, 1e-9);
  EXPECT_EQ(m.at("heart_rate_bpm"), 70.0);
  // Filling pressure of a healthy LV (normal end-diastolic pressure < 12 mmHg).
  EXPECT_GT(m.at("lv_end_diastolic_pressure_mmhg"), 3.0);
  EXPECT_LT(m.at("lv_end_diastolic_pressure_mmhg"), 12.0);
  // Valve timing near the seed's (aortic closure t/T ~ 0.35, mitral opening ~ 0.42).
  EXPECT_NEAR(m.at("aortic_valve_close_phase"), 0.35, 0.03);
  EXPECT_NEAR(m.at("mitral_valve_open_phase"), 0.42, 0.03);
  EXPECT_LT(m.at("aortic_valve_open_phase"), m.at("aortic_valve_close_phase"));
  EXPECT_LT(m.at("aortic_valve_close_phase"), m.at("mitral_valve_open_phase"));
  // Periodic state within the default beats.
  EXPECT_EQ(m.at("periodic"), 1.0);
  EXPECT_LT(m.at("edv_relative_change"), 1e-4);
  EXPECT_LE(m.at("beats_simulated"), s.beats);
  EXPECT_EQ(m.at("cancelled"), 0.0);
  EXPECT_EQ(m.count("wall_time_s"), 0u);
  for (const auto& [key, value] : m) EXPECT_TRUE(std::isfinite(value)) << key;
}

// ---- trends ------------------------------------------------------------------------------

double run_metric(const config::Scenario& s, const char* key) {
  return simulate(s).metrics.at(key);
}

TEST(LumpedTrends, HigherHeartRateRaisesCardiacOutput) {
  config::Scenario s = quiet_default();
  const double co70 = run_metric(s, "cardiac_output_l_min");
  s.heart_rate_bpm = 90;
  const double co90 = run_metric(s, "cardiac_output_l_min");
  EXPECT_GT(co90, co70 * 1.02);
}

TEST(LumpedTrends, StifferLvLowersEdv) {
  config::Scenario s = quiet_default();
  const double edv = run_metric(s, "edv_ml");
  s.lumped.lv.emin_mmhg_per_ml *= 2;
  const double edv_stiff = run_metric(s, "edv_ml");
  EXPECT_LT(edv_stiff, edv * 0.95);
}

TEST(LumpedTrends, HigherSystemicResistanceRaisesMeanAorticPressure) {
  config::Scenario s = quiet_default();
  const double map = run_metric(s, "aortic_pressure_mean_mmhg");
  s.lumped.systemic_resistance_mmhg_s_per_ml *= 1.5;
  const double map_high = run_metric(s, "aortic_pressure_mean_mmhg");
  EXPECT_GT(map_high, map + 5.0);
}

TEST(LumpedTrends, StrongerLvEjectsMore) {
  config::Scenario s = quiet_default();
  const double ef = run_metric(s, "ejection_fraction_percent");
  s.lumped.lv.emax_mmhg_per_ml *= 1.5;
  EXPECT_GT(run_metric(s, "ejection_fraction_percent"), ef + 2.0);
}

// ---- conservation ------------------------------------------------------------------------

void expect_volume_conserved(const config::Scenario& s, double dt_s, int beats) {
  Circulation c(s);
  const double v0 = c.readout().total_volume_ml;
  const std::vector<double> grid = beat_step_grid_s(c, dt_s);
  double worst = 0;
  for (int b = 0; b < beats; ++b)
    for (size_t i = 1; i < grid.size(); ++i) {
      c.advance(grid[i] - grid[i - 1]);
      worst = std::max(worst, std::abs(c.readout().total_volume_ml - v0));
    }
  // Round-off only: a few ulps of the volume per step, accumulated.
  EXPECT_LT(worst, 1e-10 * v0) << "drift " << worst << " ml of " << v0 << " ml";
}

TEST(LumpedConservation, TotalBloodVolumeIsConstantToRoundOff) {
  expect_volume_conserved(config::default_scenario(), 0.5e-3, 3);
}

TEST(LumpedConservation, AlsoWithInertialValves) {
  config::Scenario s = config::default_scenario();
  s.lumped.mitral_inertance_mmhg_s2_per_ml = 2e-4;
  s.lumped.aortic_inertance_mmhg_s2_per_ml = 5e-4;
  expect_volume_conserved(s, 0.1e-3, 2);
}

TEST(LumpedInertance, InertialValvesGiveAFiniteHealthyLoop) {
  config::Scenario s = quiet_default();
  s.lumped.mitral_inertance_mmhg_s2_per_ml = 2e-4;
  s.lumped.aortic_inertance_mmhg_s2_per_ml = 5e-4;
  s.lumped.time_step_ms = 0.1;
  const RunResult r = simulate(s);
  for (const auto& [key, value] : r.metrics) EXPECT_TRUE(std::isfinite(value)) << key;
  EXPECT_GT(r.metrics.at("ejection_fraction_percent"), 40);
  EXPECT_LT(r.metrics.at("ejection_fraction_percent"), 75);
  // A closed inertial valve passes at most its leak: no large reverse aortic flow.
  Circulation c(s);
  const std::vector<double> grid = beat_step_grid_s(c, 0.1e-3);
  for (size_t i = 1; i < grid.size(); ++i) {
    c.advance(grid[i] - grid[i - 1]);
    EXPECT_GT(c.readout().aortic_flow_ml_s, -1.0) << "t = " << c.time_s();
  }
}

// ---- external chambers -------------------------------------------------------------------

// Runs an elastance circulation for two beats, then a second circulation whose LV (and
// optionally LA) volumes are imposed from the first, step by step; returns the largest
// differences of the readouts.
struct Discrepancy {
  double lv_pressure = 0, la_pressure = 0, aortic_pressure = 0, flow = 0, total_volume = 0;
};

Discrepancy replay(double dt_s, bool lv, bool la) {
  const config::Scenario s = config::default_scenario();
  Circulation reference(s);
  const std::vector<double> grid = beat_step_grid_s(reference, dt_s);
  std::vector<Readout> recorded{reference.readout()};
  for (int b = 0; b < 2; ++b)
    for (size_t i = 1; i < grid.size(); ++i) {
      reference.advance(grid[i] - grid[i - 1]);
      recorded.push_back(reference.readout());
    }
  auto volumes = [&](const Readout& r) {
    ExternalVolumes e;
    if (lv) e.lv_ml = r.lv_volume_ml;
    if (la) e.la_ml = r.la_volume_ml;
    return e;
  };
  Circulation external(s, volumes(recorded[0]));
  EXPECT_EQ(external.lv_external(), lv);
  EXPECT_EQ(external.la_external(), la);
  Discrepancy d;
  size_t k = 0;
  for (int b = 0; b < 2; ++b)
    for (size_t i = 1; i < grid.size(); ++i) {
      ++k;
      external.advance(grid[i] - grid[i - 1], volumes(recorded[k]));
      const Readout r = external.readout();
      const Readout& e = recorded[k];
      d.lv_pressure = std::max(d.lv_pressure, std::abs(r.lv_pressure_mmhg - e.lv_pressure_mmhg));
      d.la_pressure = std::max(d.la_pressure, std::abs(r.la_pressure_mmhg - e.la_pressure_mmhg));
      d.aortic_pressure =
          std::max(d.aortic_pressure, std::abs(r.aortic_pressure_mmhg - e.aortic_pressure_mmhg));
      d.flow = std::max({d.flow, std::abs(r.mitral_flow_ml_s - e.mitral_flow_ml_s),
                         std::abs(r.aortic_flow_ml_s - e.aortic_flow_ml_s)});
      d.total_volume = std::max(d.total_volume, std::abs(r.total_volume_ml - e.total_volume_ml));
      if (lv) {
        EXPECT_GT(r.lv_outflow_conductance_ml_s_per_mmhg, 0);
      }
    }
  return d;
}

TEST(LumpedExternal, ImposedLvVolumeRecoversTheElastanceRun) {
  // The external chamber sees the volume rate of each step (a secant), so it recovers the
  // elastance run to first order in dt: errors halve with the step, and are small at 0.1 ms
  // (largest at valve closure, where the flow changes fastest).
  const Discrepancy coarse = replay(0.1e-3, true, false);
  const Discrepancy fine = replay(0.05e-3, true, false);
  EXPECT_LT(coarse.lv_pressure, 0.5);
  EXPECT_LT(coarse.aortic_pressure, 0.5);
  EXPECT_LT(coarse.la_pressure, 0.5);
  EXPECT_LT(coarse.flow, 25.0);  // ml/s, against peak valve flows of ~600 ml/s
  EXPECT_LT(coarse.total_volume, 1e-6);
  const double ratio = fine.lv_pressure / coarse.lv_pressure;
  EXPECT_GT(ratio, 0.35) << "first order expected";
  EXPECT_LT(ratio, 0.65) << "first order expected";
}

TEST(LumpedExternal, ImposedLvAndLaVolumesRecoverTheElastanceRun) {
  const Discrepancy d = replay(0.1e-3, true, true);
  EXPECT_LT(d.lv_pressure, 0.5);
  EXPECT_LT(d.la_pressure, 0.5);
  EXPECT_LT(d.aortic_pressure, 0.5);
  EXPECT_LT(d.flow, 25.0);
  EXPECT_LT(d.total_volume, 1e-6);
}

TEST(LumpedExternal, ImposedLaVolumeRecoversTheElastanceRun) {
  const Discrepancy d = replay(0.1e-3, false, true);
  EXPECT_LT(d.lv_pressure, 0.5);
  EXPECT_LT(d.la_pressure, 0.5);
  EXPECT_LT(d.flow, 25.0);
}

TEST(LumpedExternal, RejectsWhatWouldLeaveThePressureUndefined) {
  config::Scenario s = config::default_scenario();
  ExternalVolumes lv{120.0, std::nullopt};
  s.lumped.aortic_inertance_mmhg_s2_per_ml = 1e-3;
  EXPECT_THROW(Circulation(s, lv), InputError);
  s = config::default_scenario();
  s.lumped.valve_backflow_conductance_fraction = 0;
  EXPECT_THROW(Circulation(s, lv), InputError);
  s = config::default_scenario();
  Circulation c(s, lv);
  EXPECT_THROW(c.advance(1e-4), std::invalid_argument);  // volume missing
  EXPECT_THROW(c.advance(1e-4, {-1.0, std::nullopt}), std::invalid_argument);
  EXPECT_THROW(c.advance(0.0, lv), std::invalid_argument);
}

// ---- instability -------------------------------------------------------------------------

TEST(LumpedInstability, BlowUpIsReportedNotReturnedAsNaN) {
  // Valid parameters, absurd combination: near-zero valve resistances make the loop stiff
  // (rate ~ E / R ~ 1e6 /s) far beyond what explicit RK4 at 0.5 ms can follow.
  config::Scenario s = quiet_default();
  s.lumped.mitral_resistance_mmhg_s_per_ml = 1e-6;
  s.lumped.aortic_resistance_mmhg_s_per_ml = 1e-6;
  s.lumped.aortic_characteristic_impedance_mmhg_s_per_ml = 0;
  try {
    simulate(s);
    FAIL() << "expected InstabilityError";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "lumped");
    EXPECT_FALSE(e.place().empty());
    EXPECT_GT(e.time_s(), 0.0);
    EXPECT_TRUE(std::isfinite(e.time_s()));
  }
}

TEST(LumpedInstability, HugeTimeStepIsCaught) {
  const config::Scenario s = config::default_scenario();
  Circulation c(s);
  EXPECT_THROW(
      {
        for (int i = 0; i < 100; ++i) c.advance(0.5);
      },
      InstabilityError);
}

// ---- driver: cancellation, callbacks, outputs --------------------------------------------

TEST(LumpedDriver, CancelStopsTheRunCleanly) {
  config::Scenario s = quiet_default();
  s.periodicity_tolerance = 0;
  s.beats = 30;
  int calls = 0;
  const RunResult r = simulate(
      s, [&](const ProgressReport&) { ++calls; }, [&] { return calls >= 2; });
  EXPECT_EQ(calls, 2);
  EXPECT_EQ(r.metrics.at("cancelled"), 1.0);
  EXPECT_EQ(r.metrics.at("beats_simulated"), 2.0);
  EXPECT_EQ(r.metrics.at("periodic"), 0.0);
  EXPECT_EQ(r.beats.size(), 2u);
  EXPECT_GT(r.metrics.at("edv_ml"), 0.0);  // the completed beats are kept
}

TEST(LumpedDriver, CancelBeforeTheFirstBeat) {
  const RunResult r = simulate(quiet_default(), {}, [] { return true; });
  EXPECT_EQ(r.metrics.at("cancelled"), 1.0);
  EXPECT_EQ(r.metrics.at("beats_simulated"), 0.0);
  EXPECT_TRUE(r.beats.empty());
}

TEST(LumpedDriver, ReportsEveryBeat) {
  config::Scenario s = quiet_default();
  s.periodicity_tolerance = 0;
  s.beats = 4;
  std::vector<ProgressReport> reports;
  const RunResult r = simulate(s, [&](const ProgressReport& p) { reports.push_back(p); });
  ASSERT_EQ(reports.size(), 4u);
  for (int i = 0; i < 4; ++i) {
    EXPECT_EQ(reports[i].beat, i + 1);
    EXPECT_EQ(reports[i].beats_total, 4);
    EXPECT_NEAR(reports[i].simulated_time_s, (i + 1) * 60.0 / 70.0, 1e-12);
    EXPECT_NEAR(reports[i].fraction, (i + 1) / 4.0, 1e-12);
    EXPECT_GT(reports[i].latest_beat_metrics.at("ejection_fraction_percent"), 0.0);
  }
  ASSERT_EQ(r.beats.size(), 4u);
  EXPECT_EQ(r.beats[3].at("beat"), 4.0);
  EXPECT_EQ(r.metrics.at("beats_simulated"), 4.0);
  EXPECT_EQ(r.metrics.at("periodic"), 0.0);  // tolerance 0: never declared periodic
}

TEST(LumpedDriver, TimeSeriesLayoutAndSampling) {
  config::Scenario s = config::default_scenario();
  s.periodicity_tolerance = 0;
  s.beats = 3;
  s.outputs.time_series_interval_ms = 2;
  s.outputs.time_series_last_beats = 2;
  const RunResult r = simulate(s);
  const std::vector<std::string> names{
      "time_s",       "lv_pressure_mmhg",     "lv_volume_ml",     "la_pressure_mmhg",
      "la_volume_ml", "aortic_pressure_mmhg", "mitral_flow_ml_s", "aortic_flow_ml_s"};
  ASSERT_EQ(r.series.size(), names.size());
  const double period = 60.0 / 70.0;
  const size_t per_beat = static_cast<size_t>(std::ceil(period / 2e-3));
  for (size_t k = 0; k < names.size(); ++k) {
    EXPECT_EQ(r.series[k].name, names[k]);
    EXPECT_EQ(r.series[k].values.size(), 2 * per_beat) << names[k];
  }
  const auto& t = r.series[0].values;
  EXPECT_NEAR(t.front(), period, 1e-12);  // last two of three beats
  for (size_t i = 1; i < per_beat; ++i) EXPECT_NEAR(t[i] - t[i - 1], 2e-3, 1e-12);
  EXPECT_LT(t.back(), 3 * period);
  // Sampled LV volume stays between the beat's ESV and EDV (up to the isovolumic leak).
  for (double v : r.series[2].values) {
    EXPECT_GT(v, r.metrics.at("esv_ml") - 0.1);
    EXPECT_LT(v, r.metrics.at("edv_ml") + 0.1);
  }

  s.outputs.time_series_last_beats = 0;
  EXPECT_EQ(simulate(s).series[0].values.size(), 3 * per_beat);
  s.outputs.time_series = false;
  s.outputs.metrics = false;
  const RunResult bare = simulate(s);
  EXPECT_TRUE(bare.series.empty());
  EXPECT_TRUE(bare.beats.empty());
  EXPECT_GT(bare.metrics.at("ejection_fraction_percent"), 0.0);
}

}  // namespace
}  // namespace systole::lumped
