// Cell models: registry, parameters by name, declared stability limits, and the single-cell
// action potential paced at 1 Hz compared with published / physiological values.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "solver/core/errors.h"
#include "solver/electro/ionic/cell_model.h"
#include "solver/electro/single_cell.h"

namespace systole::electro {
namespace {

TEST(CellModelRegistry, ListsEveryModelAndBuildsIt) {
  const auto& names = ionic::cell_model_names();
  ASSERT_GE(names.size(), 4u);
  for (const auto& n : names) {
    auto m = ionic::make_cell_model(n, 3);
    EXPECT_EQ(m->size(), 3u);
    EXPECT_EQ(m->state_count(), m->state_names().size());
    EXPECT_GT(m->max_stable_dt_ms(), 0.0);
    EXPECT_LT(m->resting_potential_mv(), m->peak_potential_mv());
  }
}

TEST(CellModelRegistry, UnknownNameListsTheKnownOnes) {
  try {
    (void)ionic::make_cell_model("TTP6", 1);
    FAIL() << "no error";
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("'TTP6'"), std::string::npos) << m;
    for (const auto& n : ionic::cell_model_names()) EXPECT_NE(m.find(n), std::string::npos) << m;
  }
}

TEST(CellModelParameters, OverridableByNameAndUnknownIsAnError) {
  auto m = ionic::make_cell_model("ttp06_epi", 1);
  EXPECT_DOUBLE_EQ(m->parameter("GKs"), 0.392);
  m->set_parameter("GKs", 0.2);
  EXPECT_DOUBLE_EQ(m->parameter("GKs"), 0.2);
  EXPECT_THROW(m->set_parameter("gks_typo", 1.0), InputError);
  EXPECT_DOUBLE_EQ(ionic::make_cell_model("ttp06_mid", 1)->parameter("GKs"), 0.098);
  EXPECT_DOUBLE_EQ(ionic::make_cell_model("ttp06_endo", 1)->parameter("Gto"), 0.073);
}

TEST(CellModelParameters, ReducingIKsProlongsTheActionPotential) {
  // A parameter override must reach the dynamics: GKs = 0.098 (M cell value) on an epi cell.
  const PacingProtocol pr{1000.0, 3, 0.02, 52.0, 1.0};
  const auto base = pace_single_cell("ttp06_epi", pr);
  const auto mid = pace_single_cell("ttp06_mid", pr);
  EXPECT_GT(mid.apd90_ms, base.apd90_ms + 50.0);
}

TEST(SingleCell, RushLarsenIsExactForAFrozenGate) {
  const double x = ionic::rush_larsen(0.2, 1.0, 10.0, 5.0);
  EXPECT_NEAR(x, 1.0 - 0.8 * std::exp(-0.5), 1e-15);
}

// TTP06 at 1 Hz, 10 beats (the long pacing is in bench/electro; docs/electro.md lists how
// much the biomarkers still move). The bands are physiological plausibility bands (ours), not
// a reproduction of the paper's figures (which could not be retrieved). The one compilation of
// human adult myocyte data found (PMC4635107 Table 1: APD 228-259 ms, amplitude 102-110 mV, Vmax
// 254-303 V/s, rest ~-90 mV) disagrees with TTP06 (305 ms, 125 mV, 385 V/s, -85.5 mV): that is
// tabulated and discussed in docs/electro.md and deliberately not asserted here (it would fail;
// a tolerance picked to pass would be meaningless).
// - rest -90..-80 mV, peak +20..+50 mV, dV/dt max 200..450 V/s: the ranges of human
//   ventricular myocyte action potentials the model was built to match;
// - APD90 epi/endo 250..350 ms: around the ~270 ms human tissue APD that ten Tusscher et al.
//   2004 (AJP-Heart 286:H1573, Introduction) fit, with room for the single-cell prolongation;
// - M cell APD90 at least 60 ms longer than epi: the transmural gradient the 2006 model
//   is built to show (GKs 0.098 vs 0.392 nS/pF).
TEST(SingleCell, Ttp06PacedAt1HzHasPhysiologicalBiomarkers) {
  const PacingProtocol pr{1000.0, 10, 0.02, 52.0, 1.0};
  double apd_epi = 0;
  for (const char* name : {"ttp06_epi", "ttp06_endo", "ttp06_mid"}) {
    SCOPED_TRACE(name);
    const auto b = pace_single_cell(name, pr);
    EXPECT_GT(b.rest_mv, -90.0);
    EXPECT_LT(b.rest_mv, -80.0);
    EXPECT_GT(b.peak_mv, 20.0);
    EXPECT_LT(b.peak_mv, 50.0);
    EXPECT_GT(b.dvdt_max_v_per_s, 200.0);
    EXPECT_LT(b.dvdt_max_v_per_s, 450.0);
    EXPECT_LT(b.apd50_ms, b.apd90_ms);
    if (std::string(name) == "ttp06_mid") {
      EXPECT_GT(b.apd90_ms, apd_epi + 60.0);
    } else {
      EXPECT_GT(b.apd90_ms, 250.0);
      EXPECT_LT(b.apd90_ms, 350.0);
      apd_epi = b.apd90_ms;
    }
  }
}

// The cheap models: every stimulus at 1 Hz gives one full AP that repolarises before the next
// (APD90 between 150 and 400 ms: the ventricular/atrial range they are scaled to represent),
// rest at the declared resting potential.
TEST(SingleCell, CheapModelsFireAndRecoverAt1Hz) {
  for (const char* name : {"aliev_panfilov", "mitchell_schaeffer", "fhn", "fhn_atrial"}) {
    SCOPED_TRACE(name);
    auto m = ionic::make_cell_model(name, 1);
    const auto b = pace_single_cell(name, {1000.0, 3, 0.05, 35.0, 2.0});
    EXPECT_NEAR(b.rest_mv, m->resting_potential_mv(), 1.0);
    EXPECT_GT(b.peak_mv, m->resting_potential_mv() + 80.0);
    EXPECT_GT(b.apd90_ms, 150.0);
    EXPECT_LT(b.apd90_ms, 400.0);
  }
}

// fhn_atrial (ours) is the Sundnes FHN with the Vm equation 30x faster and a slower recovery
// (b = 0.006 /ms): same rest, a steeper upstroke, and an atrial APD90 in the 150-250 ms range
// issue #4 asks for (the Sundnes set at this b would be ~190 ms too, but conducts at 0.13 m/s:
// tissue_test.cc FhnAtrialConductsAtTheHumanAtrialVelocity).
TEST(SingleCell, FhnAtrialHasAnAtrialActionPotential) {
  const PacingProtocol pr{1000.0, 3, 0.01, 35.0, 2.0};
  const auto base = pace_single_cell("fhn", pr), atrial = pace_single_cell("fhn_atrial", pr);
  std::printf("fhn: dV/dt %.0f V/s, APD90 %.1f ms; fhn_atrial: dV/dt %.0f V/s, APD90 %.1f ms\n", base.dvdt_max_v_per_s,
              base.apd90_ms, atrial.dvdt_max_v_per_s, atrial.apd90_ms);
  EXPECT_NEAR(atrial.rest_mv, base.rest_mv, 0.1);
  EXPECT_GT(atrial.dvdt_max_v_per_s, 3.0 * base.dvdt_max_v_per_s);
  EXPECT_GT(atrial.apd90_ms, 150.0);
  EXPECT_LT(atrial.apd90_ms, 250.0);
}

// Mitchell & Schaeffer 2003 (Bull Math Biol 65:767, their APD analysis) derive the AP duration
// of their model to leading order in tau_in << tau_out << tau_open, tau_close: the excited state
// exists while h > h_min = 4 tau_in / tau_out, and h decays as exp(-t / tau_close) during the AP,
// so a beat from rest (h = 1) lasts APD_max = tau_close ln(1 / h_min) (= 241.4 ms by default).
// Check (ours): the measured APD90 exceeds it by the slow passage through the fold of the fast
// equation at h = h_min, which the leading order omits; with the Riccati normal form
// y' = t / (2 tau_out tau_close) + 2 y^2 / tau_out of that fold (ours) the delay is
// 2.338 (tau_out^2 tau_close)^(1/3) (2.338 = first zero of Ai(-t)), so
//   - APD90 / APD_max - 1 -> 0 as tau_close^(-2/3): observed order asserted 0.6-0.75 (2/3);
//   - APD90 within 2 % of APD_max + the delay at every tau_close.
TEST(SingleCell, MitchellSchaefferApdMatchesThePublishedAsymptoticFormula) {
  const double tau_in = 0.3, tau_out = 6.0, h_min = 4.0 * tau_in / tau_out;
  const double tcs[3] = {150.0, 600.0, 2400.0};
  double rel[3];
  for (int k = 0; k < 3; ++k) {
    const double apd_max = tcs[k] * std::log(1.0 / h_min);
    const double delay = 2.3381 * std::cbrt(tau_out * tau_out * tcs[k]);
    const auto b = pace_single_cell("mitchell_schaeffer", {apd_max + 300.0, 1, 0.02, 35.0, 2.0},
                                    {{"tau_close", tcs[k]}});
    rel[k] = b.apd90_ms / apd_max - 1.0;
    std::printf("tau_close %.0f ms: APD90 %.2f ms, APD_max %.2f ms (rel. diff %.4f), + fold delay %.2f ms\n", tcs[k],
                b.apd90_ms, apd_max, rel[k], apd_max + delay);
    EXPECT_GT(rel[k], 0.0);
    EXPECT_NEAR(b.apd90_ms / (apd_max + delay), 1.0, 0.02);
  }
  for (int k = 0; k < 2; ++k) {
    const double p = std::log(rel[k] / rel[k + 1]) / std::log(4.0);
    std::printf("observed order of APD90 / APD_max - 1 in tau_close: %.3f (theory 2/3)\n", p);
    EXPECT_GT(p, 0.6);
    EXPECT_LT(p, 0.75);
  }
}

// The declared max_stable_dt_ms is usable: paced at that step, every model gives a finite AP
// whose APD90 is within 5 % of the one at a 10x smaller step.
TEST(SingleCell, DeclaredLargestStepIsStableAndAccurate) {
  for (const auto& name : ionic::cell_model_names()) {
    SCOPED_TRACE(name);
    const double dt = ionic::make_cell_model(name, 1)->max_stable_dt_ms();
    const bool ttp = name.rfind("ttp06", 0) == 0;
    const double amp = ttp ? 52.0 : 35.0, dur = ttp ? 1.0 : 2.0;
    const auto coarse = pace_single_cell(name, {1000.0, 2, dt, amp, dur});
    const auto fine = pace_single_cell(name, {1000.0, 2, dt / 10, amp, dur});
    std::printf("%s: APD90 %.1f ms at dt %.3f, %.1f ms at dt %.4f\n", name.c_str(), coarse.apd90_ms, dt, fine.apd90_ms,
                dt / 10);
    ASSERT_TRUE(std::isfinite(coarse.apd90_ms));
    EXPECT_NEAR(coarse.apd90_ms / fine.apd90_ms, 1.0, 0.05);
  }
}

// The gate lookup table (default) against the exact gate functions: same AP to < 0.5 %.
TEST(SingleCell, Ttp06LookupTableMatchesTheExactGates) {
  auto run = [](double lut) {
    auto m = ionic::make_cell_model("ttp06_epi", 1);
    m->set_parameter("lookup_table", lut);
    double v = m->resting_potential_mv(), iion = 0, peak = -1e9, t90 = 0;
    const double dt = 0.02;
    for (int s = 0; s < 25000; ++s) {  // 500 ms
      const double stim = s * dt < 1.0 ? 52.0 : 0.0;
      m->compute({0, 1}, dt, &v, &iion);
      v += dt * (stim - iion);
      peak = std::max(peak, v);
      if (s * dt > 50 && t90 == 0 && v < -72.0) t90 = s * dt;
    }
    return std::make_pair(peak, t90);
  };
  const auto exact = run(0.0), table = run(1.0);
  std::printf("exact: peak %.3f mV, Vm < -72 mV at %.2f ms; table: %.3f mV, %.2f ms\n", exact.first, exact.second,
              table.first, table.second);
  EXPECT_NEAR(table.first, exact.first, 0.2);
  EXPECT_NEAR(table.second / exact.second, 1.0, 0.005);
}

TEST(SingleCell, TimeStepAboveTheDeclaredLimitIsRejected) {
  EXPECT_THROW((void)pace_single_cell("ttp06_epi", {1000.0, 1, 0.5, 52.0, 1.0}), InputError);
}

}  // namespace
}  // namespace systole::electro
