// Beat metrics on synthetic curves whose answers are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <vector>

#include "solver/diagnostics/beat_metrics.h"

namespace systole::diagnostics {
namespace {

// A hand-made beat of period 0.8 s sampled every 1 ms, built from straight pieces so every
// expected value is exact:
//  - mitral flow +100 ml/s until t = 0.02 s, -1 (leak) until 0.34 s, then two bumps
//    (E at 0.40 s, height 500; A at 0.72 s, height 250), back to +100 at the end;
//  - aortic flow -1 until 0.06 s, a triangle up to 400 ml/s at 0.15 s, back down crossing 0
//    at 0.28 s, -1 afterwards;
//  - LV volume falls linearly from 120 ml (t = 0.06) to 50 ml (t = 0.28), rises afterwards;
//  - LV pressure 10 + 100 sin(pi (t - 0.02) / 0.30) during systole, aortic pressure 80..120.
struct SyntheticBeat {
  std::vector<double> t, v, p, pa, qm, qa;
  static double tri(double x, double x0, double half_width, double height) {
    const double d = std::abs(x - x0) / half_width;
    return d < 1 ? height * (1 - d) : 0;
  }
  SyntheticBeat() {
    for (int i = 0; i <= 800; ++i) {
      const double s = i * 1e-3;
      t.push_back(s);
      double volume;
      if (s < 0.06)
        volume = 120;
      else if (s < 0.28)
        volume = 120 - 70 * (s - 0.06) / 0.22;
      else if (s < 0.34)
        volume = 50;
      else
        volume = 50 + 70 * (s - 0.34) / 0.46;
      v.push_back(volume);
      p.push_back(s > 0.02 && s < 0.32 ? 10 + 100 * std::sin(std::numbers::pi * (s - 0.02) / 0.30)
                                       : 10);
      pa.push_back(80 + 40 * std::exp(-std::pow((s - 0.18) / 0.08, 2)));
      double m;
      if (s < 0.02)
        m = 100 - 5000 * s;  // 100 at 0, 0 at 0.02
      else if (s < 0.34)
        m = -1;
      else
        m = tri(s, 0.40, 0.06, 500) + tri(s, 0.72, 0.06, 250) - 1 * (s < 0.34);
      if (s >= 0.34 && m <= 0) m = 2;  // open, low diastasis flow
      qm.push_back(m);
      double a = -1;
      if (s >= 0.06 && s <= 0.15)
        a = -1 + 401 * (s - 0.06) / 0.09;
      else if (s > 0.15 && s < 0.30)
        a = 400 - 400 * (s - 0.15) / 0.13;
      if (s >= 0.30) a = -1;
      qa.push_back(a);
    }
  }
  BeatSamples samples() const { return {t, v, p, pa, qm, qa, 0.0, 0.8}; }
};

TEST(BeatMetrics, BuildingBlocks) {
  EXPECT_DOUBLE_EQ(stroke_volume_ml(125, 52), 73);
  EXPECT_NEAR(ejection_fraction_percent(125, 52), 58.4, 1e-12);
  EXPECT_EQ(ejection_fraction_percent(0, 0), 0);
  EXPECT_NEAR(cardiac_output_l_min(73, 70), 5.11, 1e-12);  // 73 ml x 70 /min = 5.11 l/min
  const std::vector<double> t{0, 1, 2, 4}, y{1, 3, 3, -1};
  EXPECT_DOUBLE_EQ(integrate(t, y), 2 + 3 + 2);
  EXPECT_DOUBLE_EQ(time_average(t, y), 7.0 / 4.0);
  EXPECT_DOUBLE_EQ(*first_crossing(t, y, 2.0, Crossing::kUpward), 0.5);
  EXPECT_DOUBLE_EQ(*first_crossing(t, y, 0.0, Crossing::kDownward), 3.5);
  EXPECT_FALSE(first_crossing(t, y, 5.0, Crossing::kUpward).has_value());
  EXPECT_DOUBLE_EQ(value_at(t, y, 3.0), 1.0);
  EXPECT_DOUBLE_EQ(value_at(t, y, -1.0), 1.0);
}

TEST(BeatMetrics, SyntheticBeatGivesTheConstructedAnswers) {
  const SyntheticBeat b;
  const BeatMetrics m = compute_beat_metrics(b.samples());
  EXPECT_NEAR(m.heart_rate_bpm, 75, 1e-12);
  // Mitral closure where 100 - 5000 t crosses 0 (t = 0.02 exactly) -> phase 0.025.
  ASSERT_TRUE(m.mitral_valve.close_phase);
  EXPECT_NEAR(*m.mitral_valve.close_phase, 0.02 / 0.8, 1e-3 / 0.8);
  ASSERT_TRUE(m.mitral_valve.open_phase);
  EXPECT_NEAR(*m.mitral_valve.open_phase, 0.34 / 0.8, 1e-3 / 0.8);
  // Aortic opening where -1 + 401 (t - 0.06)/0.09 = 0, closing where 400 - 400 (t-0.15)/0.13
  // crosses 0 (t = 0.28).
  ASSERT_TRUE(m.aortic_valve.open_phase);
  EXPECT_NEAR(*m.aortic_valve.open_phase, (0.06 + 0.09 / 401) / 0.8, 1e-3 / 0.8);
  ASSERT_TRUE(m.aortic_valve.close_phase);
  EXPECT_NEAR(*m.aortic_valve.close_phase, 0.28 / 0.8, 1e-3 / 0.8);
  // End-diastole at mitral closure (V = 120), end-systole at aortic closure (V = 50).
  EXPECT_NEAR(m.edv_ml, 120, 1e-9);
  EXPECT_NEAR(m.esv_ml, 50, 1e-6);
  EXPECT_NEAR(m.ejection_fraction_percent, 100.0 * 70 / 120, 1e-5);
  EXPECT_NEAR(m.cardiac_output_l_min, 70 * 75 / 1000.0, 1e-6);
  EXPECT_NEAR(m.lv_end_diastolic_pressure_mmhg, 10, 1e-9);
  EXPECT_NEAR(m.lv_peak_pressure_mmhg, 110, 1e-6);
  EXPECT_NEAR(m.lv_peak_pressure_phase, 0.17 / 0.8, 1e-12);
  EXPECT_NEAR(m.aortic_pressure_max_mmhg, 120, 1e-9);
  // The Gaussian bump over [0, 0.8] integrates to 40 * 0.08 sqrt(pi) (1 - erfc(2.25) / 2)
  // (the right tail beyond 0.8 s is below 1e-20).
  EXPECT_NEAR(
      m.aortic_pressure_mean_mmhg,
      80 + 40 * 0.08 * std::sqrt(std::numbers::pi) * (1 - 0.5 * std::erfc(0.18 / 0.08)) / 0.8,
      1e-5);
  ASSERT_TRUE(m.mitral_e_peak_phase && m.mitral_a_peak_phase);
  EXPECT_NEAR(*m.mitral_e_peak_phase, 0.40 / 0.8, 1e-9);
  EXPECT_NEAR(*m.mitral_a_peak_phase, 0.72 / 0.8, 1e-9);
  EXPECT_NEAR(*m.mitral_e_peak_flow_ml_s, 500, 1e-6);
  EXPECT_NEAR(*m.mitral_a_peak_flow_ml_s, 250, 1e-6);
  const auto map = to_map(m);
  EXPECT_NEAR(map.at("mitral_e_to_a_ratio"), 2.0, 1e-9);
  EXPECT_EQ(map.count("aortic_valve_close_phase"), 1u);
}

// A 30-ml/s dip on the E wave's rise (a 3-D flow's ripple, as in run P3 of docs/fsei.md) makes a
// local maximum of 166.7 ml/s at 0.36 s, above the 10 % floor (50 ml/s) but standing out by only
// 30 ml/s: the E wave is still the crest at 0.40 s, and A is unchanged.
TEST(BeatMetrics, ARippleOnTheEWavesRiseIsNotTheEWave) {
  SyntheticBeat b;
  const size_t crest = 360;  // t = 0.360 s: 500 * 0.02 / 0.06
  ASSERT_NEAR(b.qm[crest], 500.0 / 3, 1e-9);
  for (size_t i = crest + 1; i < crest + 5; ++i) b.qm[i] = b.qm[crest] - 30;
  ASSERT_GT(b.qm[crest + 5], b.qm[crest]);
  const BeatMetrics m = compute_beat_metrics(b.samples());
  ASSERT_TRUE(m.mitral_e_peak_phase && m.mitral_a_peak_phase);
  EXPECT_NEAR(*m.mitral_e_peak_phase, 0.40 / 0.8, 1e-9);
  EXPECT_NEAR(*m.mitral_e_peak_flow_ml_s, 500, 1e-6);
  EXPECT_NEAR(*m.mitral_a_peak_phase, 0.72 / 0.8, 1e-9);
  EXPECT_NEAR(*m.mitral_a_peak_flow_ml_s, 250, 1e-6);
  // A dip as deep as the floor makes the ripple a wave of its own: it is then E, and the
  // largest later crest (500 ml/s) is reported as A.
  for (size_t i = crest + 1; i < crest + 5; ++i) b.qm[i] = b.qm[crest] - 60;
  const BeatMetrics two = compute_beat_metrics(b.samples());
  ASSERT_TRUE(two.mitral_e_peak_flow_ml_s && two.mitral_a_peak_flow_ml_s);
  EXPECT_NEAR(*two.mitral_e_peak_flow_ml_s, 500.0 / 3, 1e-9);
  EXPECT_NEAR(*two.mitral_a_peak_flow_ml_s, 500, 1e-6);
}

TEST(BeatMetrics, MissingEventsAreLeftOutNotNaN) {
  std::vector<double> t{0, 0.5, 1}, v{100, 100, 100}, p{5, 5, 5}, q{0, 0, 0};
  const BeatMetrics m = compute_beat_metrics({t, v, p, p, q, q, 0, 1});
  EXPECT_FALSE(m.aortic_valve.open_phase || m.aortic_valve.close_phase);
  const auto map = to_map(m);
  EXPECT_EQ(map.count("aortic_valve_close_phase"), 0u);
  EXPECT_EQ(map.count("mitral_e_to_a_ratio"), 0u);
  for (const auto& [key, value] : map) EXPECT_TRUE(std::isfinite(value)) << key;
  EXPECT_EQ(m.edv_ml, 100);  // fallback: largest volume
}

TEST(BeatMetrics, RejectsBadInput) {
  std::vector<double> t{0, 1}, t_bad{0, 0}, v{1, 2}, short_v{1};
  EXPECT_THROW(compute_beat_metrics({t, short_v, v, v, v, v, 0, 1}), std::invalid_argument);
  EXPECT_THROW(compute_beat_metrics({t_bad, v, v, v, v, v, 0, 1}), std::invalid_argument);
  EXPECT_THROW(compute_beat_metrics({t, v, v, v, v, v, 0, 0}), std::invalid_argument);
}

TEST(BeatMetrics, ThresholdIgnoresSmallNoise) {
  // A flow that wiggles around zero before opening: sign changes would report the wiggle,
  // a 5 % threshold reports the real opening at t = 0.5.
  std::vector<double> t, q, v, p;
  for (int i = 0; i <= 100; ++i) {
    const double s = i * 0.01;
    t.push_back(s);
    q.push_back(s < 0.5 ? 0.5 * std::sin(40 * s) : 100 * (s - 0.5) / 0.1);
    v.push_back(100);
    p.push_back(10);
  }
  EXPECT_LT(*valve_events(t, q, 0, 1, 0.0).open_phase, 0.1);
  EXPECT_NEAR(*valve_events(t, q, 0, 1, 0.05).open_phase, 0.5 + 0.05 * 500 / 100 * 0.1, 1e-9);
}

TEST(BeatMetrics, ADwellIgnoresARippleThroughTheThreshold) {
  // A 3-D valve flow (p2's mitral, docs/fsei.md session 17): it pokes above the 5 % level for
  // ~4 ms around t = 0.387 and drops back, then opens for good at t = 0.395 (linear ramps, so the
  // crossings are exact), and falls below the level again only at t = 0.95.
  std::vector<double> t, q;
  for (int i = 0; i <= 1000; ++i) {
    const double s = 1e-3 * i;
    double f = 0;
    if (s >= 0.385 && s <= 0.389) f = 20 - 8000 * std::abs(s - 0.387);  // 20 at the top, 4 at the ends
    if (s >= 0.39) f = std::min(100.0, 1000 * (s - 0.39));               // 5 at t = 0.395
    if (s >= 0.9) f = std::max(0.0, 100 - 2000 * (s - 0.9));             // 5 at t = 0.9475
    t.push_back(s);
    q.push_back(f);
  }
  // the level is 5 % of 100 = 5: the ripple crosses it at 0.387 -/+ 15/8000
  const ValveEvents any = valve_events(t, q, 0, 1, 0.05);
  EXPECT_NEAR(*any.open_phase, 0.387 - 15.0 / 8000, 1e-9);
  EXPECT_NEAR(*any.close_phase, 0.387 + 15.0 / 8000, 1e-9);
  const ValveEvents lasting = valve_events(t, q, 0, 1, 0.05, 0.02);
  EXPECT_NEAR(*lasting.open_phase, 0.395, 1e-9);
  EXPECT_NEAR(*lasting.close_phase, 0.9475, 1e-9);
  // a closure too near the window's end for the whole dwell still counts (nothing contradicts it)
  const std::span<const double> ts(t.data(), 951), qs(q.data(), 951);
  EXPECT_NEAR(*valve_events(ts, qs, 0, 1, 0.05, 0.02).close_phase, 0.9475, 1e-9);
  EXPECT_THROW(valve_events(t, q, 0, 1, 0.05, -0.1), std::invalid_argument);
}

TEST(BeatMetrics, AValveThatStartsClosedClosesOnlyAfterItOpened) {
  // The shape of run w2's aortic flow (docs/fsei.md session 20): closed at the start, a 2-ms
  // poke above the 5 % level at 18 ms (the isovolumic ripple), the ejection 0.12-0.30 s. Linear
  // pieces, so every crossing is exact. Read as "first crossing each way", the ripple's way
  // back down was the closure (0.021 T, ESV = EDV, EF -0.6 %).
  const double period = 0.857;
  std::vector<double> t, q, v, p;
  for (int i = 0; i <= 857; ++i) {
    const double s = 1e-3 * i;
    double f = 0;
    if (std::abs(s - 0.018) < 0.003) f = 30 * (1 - std::abs(s - 0.018) / 0.003);  // > 20 on 0.017..0.019
    if (s > 0.12 && s <= 0.15) f = 400 * (s - 0.12) / 0.03;                        // 20 at 0.1215
    if (s > 0.15 && s < 0.30) f = 400 * (0.30 - s) / 0.15;                         // 20 at 0.2925
    t.push_back(s);
    q.push_back(f);
    v.push_back(s < 0.12 ? 125 : s < 0.30 ? 125 - 35 * (s - 0.12) / 0.18 : 90);
    p.push_back(10);
  }
  const ValveEvents e = valve_events(t, q, 0, period, 0.05, 0.02);
  ASSERT_TRUE(e.open_phase && e.close_phase);
  EXPECT_NEAR(*e.open_phase, 0.1215 / period, 1e-9);
  EXPECT_NEAR(*e.close_phase, 0.2925 / period, 1e-9);
  BeatSamples b{t, v, p, p, q, q, 0, period};
  b.valve_threshold_fraction = 0.05;
  b.valve_min_dwell_fraction = 0.02;
  b.end_diastole_at_beat_start = true;
  const BeatMetrics m = compute_beat_metrics(b);
  EXPECT_NEAR(m.esv_ml, 125 - 35 * (0.2925 - 0.12) / 0.18, 1e-9);
  EXPECT_GT(m.ejection_fraction_percent, 25);
  // the same flow started open (the 0-D mitral at a beat that starts in diastole): the closure
  // comes first, the opening is the first lasting crossing back up after it (no ripple here:
  // within the dwell after the closure it would make that closure not last)
  std::vector<double> q_open = q;
  for (int i = 0; i <= 30; ++i) q_open[i] = std::max(0, 100 - 10 * i);  // 20 (the level) at 8 ms
  const ValveEvents o = valve_events(t, q_open, 0, period, 0.05, 0.02);
  ASSERT_TRUE(o.open_phase && o.close_phase);
  EXPECT_NEAR(*o.close_phase, 0.008 / period, 1e-9);
  EXPECT_NEAR(*o.open_phase, 0.1215 / period, 1e-9);
}

TEST(BeatMetrics, TheAWaveIsTheLargestFillingPeakAfterE) {
  // Run w2's mitral flow (docs/fsei.md session 20): E 140 ml/s at 0.43 s, A 330 ml/s at 0.81 s,
  // and a ripple of 90 ml/s at 0.84 s after the A wave that "last maximum" took for A.
  std::vector<double> t, q, v;
  for (int i = 0; i <= 857; ++i) {
    const double s = 1e-3 * i;
    double f = 0;
    if (std::abs(s - 0.43) < 0.05) f = 140 * (1 - std::abs(s - 0.43) / 0.05);
    if (std::abs(s - 0.81) < 0.02) f = 330 * (1 - std::abs(s - 0.81) / 0.02);
    if (std::abs(s - 0.84) < 0.008) f = 90 * (1 - std::abs(s - 0.84) / 0.008);
    if (s > 0.38 && f < 5) f = 5;  // open, a low diastasis flow
    t.push_back(s);
    q.push_back(f);
    v.push_back(100);
  }
  const BeatMetrics m = compute_beat_metrics({t, v, v, v, q, q, 0, 0.857});
  ASSERT_TRUE(m.mitral_e_peak_phase && m.mitral_a_peak_phase);
  EXPECT_NEAR(*m.mitral_e_peak_flow_ml_s, 140, 1e-9);
  EXPECT_NEAR(*m.mitral_a_peak_flow_ml_s, 330, 1e-9);
  EXPECT_NEAR(*m.mitral_a_peak_phase, 0.81 / 0.857, 1e-9);
}

}  // namespace
}  // namespace systole::diagnostics
