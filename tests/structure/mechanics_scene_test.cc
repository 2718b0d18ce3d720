// Scene "mechanics": a small pressurised sphere writes positions (HDF5 + XDMF), its volume grows
// monotonically under the ramp, the series agree with the metrics, and a cancel stops it.
#include <gtest/gtest.h>

#include <filesystem>

#include "solver/core/errors.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/lv_wall_readings.h"
#include "solver/scene/mechanics_scene.h"
#include "solver/scene/pv_relations.h"
#include "solver/scene/scene.h"
#include "solver/structure/shell.h"

namespace systole::scene {
namespace {

class Control final : public RunControl {
 public:
  explicit Control(std::filesystem::path dir) : dir_(std::move(dir)) {}
  void on_progress(const ProgressReport&) override { ++reports; }
  bool cancel_requested() override { return cancel; }
  std::filesystem::path output_directory() override { return dir_; }
  int reports = 0;
  bool cancel = false;

 private:
  std::filesystem::path dir_;
};

config::Scenario small_sphere() {
  return config::parse_scenario({{"scene", "mechanics"},
                                 {"structure",
                                  {{"body", "sphere"}, {"sphere_refinement", 2}, {"cavity_pressure_mmhg", 1},
                                   {"pressure_ramp_ms", 30}, {"end_time_ms", 30}, {"output_interval_ms", 3},
                                   {"damping_per_ms", 0.5}}}});
}

TEST(MechanicsScene, SphereInflatesAndWritesPositions) {
  const auto dir = std::filesystem::temp_directory_path() / "systole_mechanics_scene_test";
  std::filesystem::remove_all(dir);
  Control control(dir);
  const RunResult r = run(small_sphere(), control);
  EXPECT_EQ(control.reports, 10);
  EXPECT_TRUE(std::filesystem::exists(dir / "structure.h5"));
  EXPECT_TRUE(std::filesystem::exists(dir / "structure.xmf"));
  EXPECT_EQ(r.metrics.at("positions_written"), 1);
  EXPECT_EQ(r.metrics.at("nodes"), 162);
  EXPECT_GT(r.metrics.at("volume_final_ml"), r.metrics.at("volume_initial_ml"));
  // Series: time_s, pressure_mmhg, sphere_volume_ml, ...; 11 samples (t = 0 and 10 steps).
  ASSERT_GE(r.series.size(), 3u);
  EXPECT_EQ(r.series[0].name, "time_s");
  EXPECT_EQ(r.series[2].name, "sphere_volume_ml");
  ASSERT_EQ(r.series[2].values.size(), 11u);
  EXPECT_NEAR(r.series[2].values.back(), r.metrics.at("volume_final_ml"), 1e-12);
  EXPECT_NEAR(r.series[2].values.front(), r.metrics.at("volume_initial_ml"), 1e-12);
  std::filesystem::remove_all(dir);
}

// The procedural heart's mitral leaflets closed by 0.3 mmHg (LV over LA) with contact and the
// limiter (1 mm towards the LA): they touch, nothing crosses, the limiter holds.
TEST(MechanicsScene, MitralLeafletsCoaptWithContactAndLimiter) {
  Control control({});
  // The seed's leaflet c in pascals, soft enough for 0.3 mmHg to close them (the default reads
  // it in units of rho U^2, docs/fsei.md): the test is about contact and the limiter.
  const auto s = config::parse_scenario({{"scene", "mechanics"},
                                         {"tissue", {{"mitral_leaflets", {{"fung_c_pa", 9.7}}}}},
                                         {"structure",
                                          {{"body", "mitral_leaflets"}, {"cavity_pressure_mmhg", 0.3},
                                           {"pressure_ramp_ms", 5}, {"end_time_ms", 30}, {"output_interval_ms", 2},
                                           {"damping_per_ms", 0.3}, {"mitral_limit_mm", 1}}}});
  const RunResult r = run(s, control);
  EXPECT_GT(r.metrics.at("contact_pairs_max"), 5);
  EXPECT_EQ(r.metrics.at("contact_crossed_max"), 0);
  EXPECT_GT(r.metrics.at("contact_min_gap_mm"), 0.25);
  EXPECT_LE(r.metrics.at("leaflet_displacement_towards_la_mm"), 1.0 + 1e-9);
  EXPECT_EQ(r.metrics.count("mitral_anterior_max_strain"), 1u);
}

TEST(MechanicsScene, CancelStops) {
  Control control({});
  control.cancel = true;
  EXPECT_THROW(run(small_sphere(), control), Cancelled);
}

TEST(MechanicsScene, BadStructureInputIsRejectedByTheTable) {
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"law", "hooke"}}}}), InputError);
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"shell_thickness_mm", -1}}}}),
               InputError);
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"tissue", {{"lv", {{"fung_c_pa", -13.3}}}}}}),
               InputError);
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"contact_distance_mm", 0}}}}),
               InputError);
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"contact_stiffness_kpa_per_mm", -1}}}}),
               InputError);
}


// structure.walls = "chamber" builds the LV and LA walls: any other body is refused at parse,
// naming the field, the value and what is allowed.
TEST(MechanicsScene, ChamberWallsNeedAnLvBody) {
  try {
    config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"walls", "chamber"}, {"body", "sphere"}}}});
    FAIL() << "accepted structure.walls = chamber with a sphere";
  } catch (const InputError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("structure.walls"), std::string::npos) << what;
    EXPECT_NE(what.find("sphere"), std::string::npos) << what;
    EXPECT_NE(what.find("lv, left_heart"), std::string::npos) << what;
  }
  EXPECT_NO_THROW(
      config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"walls", "chamber"}, {"body", "lv"}}}}));
}

// The membrane triangles take the printed law, and not the aorta's pre-stress (which sets the
// springs' rest lengths): refused at parse.
TEST(MechanicsScene, MembraneTrianglesRefuseWhatTheyCannotCarry) {
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"},
                                       {"structure", {{"membrane", "triangles"}, {"law", "linear"}}}}),
               InputError);
  EXPECT_NO_THROW(config::parse_scenario({{"scene", "mechanics"},
                                          {"structure", {{"membrane", "triangles"}, {"law", "fung"}}}}));
  EXPECT_THROW(config::parse_scenario({{"scene", "fsi"},
                                       {"structure", {{"membrane", "triangles"}, {"law", "fung"}}},
                                       {"electromechanics", {{"spring_law", "fung"}}},
                                       {"fsei", {{"aorta", {{"pretension", "prestress"}}}}}}),
               InputError);
}

// The LV wall's readings on motions with known answers: a uniform scaling by 0.9 about the base
// centre gives every edge eps = (l - l0)/l = -0.1/0.9, global strains of -10 %, a fibre stretch
// of 0.9 and no twist; a rigid rotation about the long axis gives no strain and no twist.
TEST(LvWallReadings, ExactOnScalingAndRotation) {
  const config::Scenario s = config::default_scenario();
  const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
  structure::ShellModel lv(heart.body(geometry::kLvBody), structure::materials_from_config(s.tissue),
                           structure::ShellOptions{});
  const geometry::ApexBaseAxis axis = geometry::apex_base_axis(lv.stress_free_mesh());
  const std::vector<structure::Vec3> x0 = lv.positions_mm();
  const std::vector<structure::Vec3> v0(x0.size(), structure::Vec3::Zero());

  std::vector<structure::Vec3> x = x0;
  for (auto& p : x) p = axis.base_centre_mm + 0.9 * (p - axis.base_centre_mm);
  lv.set_state(x, v0);
  std::map<std::string, double> m;
  add_lv_wall_readings(lv, "lv_", m);
  const double eps = -0.1 / 0.9;
  for (const char* dir : {"fibre", "cross", "oblique"}) {
    EXPECT_GT(m.at(std::string("lv_edges_") + dir), 0) << dir;
    EXPECT_NEAR(m.at(std::string("lv_edge_strain_") + dir + "_min"), eps, 1e-9) << dir;
    EXPECT_NEAR(m.at(std::string("lv_edge_strain_") + dir + "_max"), eps, 1e-9) << dir;
  }
  EXPECT_NEAR(m.at("lv_gcs_percent"), -10, 1e-9);
  EXPECT_NEAR(m.at("lv_gls_percent"), -10, 1e-9);
  EXPECT_NEAR(m.at("lv_twist_deg"), 0, 1e-9);
  EXPECT_NEAR(m.at("lv_fibre_stretch_mean"), 0.9, 1e-9);

  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.3, axis.direction).toRotationMatrix();
  x = x0;
  for (auto& p : x) p = axis.base_centre_mm + r * (p - axis.base_centre_mm);
  lv.set_state(x, v0);
  m.clear();
  add_lv_wall_readings(lv, "lv_", m);
  EXPECT_NEAR(m.at("lv_gcs_percent"), 0, 1e-9);
  EXPECT_NEAR(m.at("lv_gls_percent"), 0, 1e-9);
  EXPECT_NEAR(m.at("lv_twist_deg"), 0, 1e-9);
  EXPECT_NEAR(m.at("lv_fibre_stretch_mean"), 1, 1e-9);
  EXPECT_NEAR(m.at("lv_edge_strain_fibre_min"), 0, 1e-9);
}


// The fits on exact relations: P = 2.5 (V - 20) and P = 1.8 (exp(0.045 (V - 110)) - 1).
TEST(PvRelations, FitsRecoverExactRelations) {
  std::vector<PvPoint> es, ed{{0, 110}};
  for (double v : {50.0, 60.0, 75.0}) es.push_back({2.5 * (v - 20), v});
  for (double v : {120.0, 135.0, 150.0, 170.0}) ed.push_back({1.8 * std::expm1(0.045 * (v - 110)), v});
  const EspvrFit f = fit_espvr(es);
  EXPECT_NEAR(f.e_es_mmhg_per_ml, 2.5, 1e-12);
  EXPECT_NEAR(f.v0_ml, 20, 1e-10);
  EXPECT_NEAR(f.r2, 1, 1e-12);
  const EdpvrFit g = fit_edpvr(ed);
  EXPECT_NEAR(g.v0_ml, 110, 0);
  EXPECT_NEAR(g.beta_per_ml, 0.045, 1e-7);
  EXPECT_NEAR(g.a_mmhg, 1.8, 1e-5);
  EXPECT_LT(g.rms_mmhg, 1e-6);
  EXPECT_THROW(fit_espvr({{80, 60}}), std::invalid_argument);
  EXPECT_THROW(fit_edpvr({{5, 110}, {10, 120}, {20, 130}}), std::invalid_argument);  // no unloaded point
}

// Protocol pv_relations on the coupled scenes' walls: the EDPVR rises, the ESPVR rises with a
// positive E_es, and its point at 80 mmHg is the equilibrium that a single ramp to the same loads
// reaches (a different load path: the points are states at rest, not path artefacts).
TEST(MechanicsScene, PvRelationsMatchASingleRampToTheSameLoads) {
  const nlohmann::json base = {{"scene", "mechanics"},
                               {"geometry", {{"target_edge_mm", 4}}},  // a coarse LV: a cheap test
                               {"structure",
                                {{"body", "lv"}, {"walls", "chamber"}, {"active_tension_kpa", 120},
                                 {"pressure_ramp_ms", 20}, {"output_interval_ms", 2}, {"end_time_ms", 300},
                                 {"write_positions", false}}}};
  nlohmann::json pv = base;
  pv["structure"]["protocol"] = "pv_relations";
  pv["structure"]["pv_points"] = 2;
  pv["structure"]["edpvr_max_mmhg"] = 20;
  pv["structure"]["espvr_min_mmhg"] = 80;
  pv["structure"]["espvr_max_mmhg"] = 110;
  Control control({});
  const RunResult r = run(config::parse_scenario(pv), control);
  const auto& m = r.metrics;
  EXPECT_EQ(control.reports, 4);
  EXPECT_GT(m.at("edpvr_volume_at_max_ml"), m.at("edpvr_v0_ml") + 10);
  EXPECT_GT(m.at("edpvr_beta_per_ml"), 0);
  EXPECT_GT(m.at("espvr_e_es_mmhg_per_ml"), 0);
  EXPECT_GT(m.at("espvr_volume_at_max_ml"), m.at("espvr_volume_at_min_ml"));
  for (const auto& name : mechanics_metric_names()) EXPECT_TRUE(m.count(name)) << name;  // campaigns can name them
  nlohmann::json ramp = base;
  ramp["structure"]["cavity_pressure_mmhg"] = 80;
  Control c2({});
  const RunResult single = run(config::parse_scenario(ramp), c2);
  EXPECT_NEAR(m.at("espvr_volume_at_min_ml"), single.metrics.at("lv_volume_final_ml"), 0.05);
  EXPECT_THROW(config::parse_scenario({{"scene", "mechanics"}, {"structure", {{"protocol", "pv_relations"}}}}),
               InputError);  // body sphere
}

}  // namespace
}  // namespace systole::scene
