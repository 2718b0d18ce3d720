// Cross-field rules of the geometry variant (solver/config/geometry_rules.cc): each
// impossible combination is rejected with a message naming the fields, values and what is
// allowed; combinations the rules accept build (the two stay consistent).
#include <gtest/gtest.h>

#include <iostream>
#include <random>

#include "solver/config/geometry_rules.h"
#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/geometry/left_heart.h"

namespace systole::config {
namespace {

std::vector<std::string> rules(const Geometry& g) {
  std::vector<std::string> e;
  check_geometry_rules(g, e);
  return e;
}

void expect_rejected(const Geometry& g, const std::vector<std::string>& phrases) {
  const auto e = rules(g);
  ASSERT_FALSE(e.empty()) << "expected a rule to fire for " << phrases[0];
  bool found = false;
  for (const auto& m : e) {
    bool all = true;
    for (const auto& p : phrases) all = all && m.find(p) != std::string::npos;
    found = found || all;
  }
  std::string msgs;
  for (const auto& m : e) msgs += "\n  " + m;
  EXPECT_TRUE(found) << "no message with all of the phrases; got:" << msgs;
}

TEST(GeometryRules, DefaultsPass) { EXPECT_TRUE(rules(default_scenario().geometry).empty()); }

TEST(GeometryRules, ImpossibleCombinationsAreNamed) {
  const Geometry d = default_scenario().geometry;
  Geometry g = d;
  g.lv_volume_ml = 160;
  expect_rejected(g, {"geometry.lv_volume_ml = 160", "lv_short_axis_mm", "allowed"});
  g = d;
  g.mitral_diameter_mm = 34;
  expect_rejected(g, {"mitral_diameter_mm + geometry.aortic_diameter_mm", "do not fit in the valvular plane"});
  g = d;
  g.mitral_leaflet_length_mm = 11;
  expect_rejected(g, {"geometry.mitral_leaflet_length_mm = 11", "too short", "allowed"});
  g = d;
  g.lv_long_axis_mm = 40;
  g.lv_volume_ml = 60;
  g.mitral_leaflet_length_mm = 40;
  expect_rejected(g, {"geometry.mitral_leaflet_length_mm = 40", "longer than the LV", "allowed: <="});
  g = d;
  g.aortic_root_diameter_mm = 28;
  expect_rejected(g, {"geometry.aortic_root_diameter_mm = 28", "aortic_arch_diameter_mm = 30"});
  g = d;
  g.aortic_root_diameter_mm = 50;
  expect_rejected(g, {"geometry.aortic_root_diameter_mm = 50", "left atrium"});
  g = d;
  g.la_volume_ml = 5;
  g.mitral_diameter_mm = 30;
  expect_rejected(g, {"geometry.la_volume_ml = 5", "too small", "allowed: la_volume_ml >"});
  g = d;
  g.pulmonary_vein_diameter_mm = 20;
  expect_rejected(g, {"geometry.pulmonary_vein_diameter_mm = 20", "ostia do not fit", "allowed"});
  g = d;
  g.aortic_diameter_mm = 42;
  expect_rejected(g, {"geometry.aortic_diameter_mm = 42", "aortic_root_diameter_mm"});
  g = d;
  g.mitral_leaflet_thickness_mm = 6;
  g.mitral_leaflet_length_mm = 11.5;
  expect_rejected(g, {"geometry.mitral_leaflet_thickness_mm = 6"});
  g = d;
  g.target_edge_mm = 8;
  expect_rejected(g, {"geometry.target_edge_mm = 8", "too coarse"});
  g = d;
  g.lv_wall_mm = 30;
  expect_rejected(g, {"geometry.lv_wall_mm = 30"});
}

TEST(GeometryRules, ParseScenarioReportsThem) {
  nlohmann::json doc = {{"geometry", {{"lv_volume_ml", 170}, {"mitral_leaflet_length_mm", 8}}}};
  try {
    parse_scenario(doc);
    FAIL();
  } catch (const InputError& e) {
    const std::string w = e.what();
    EXPECT_NE(w.find("geometry.lv_volume_ml = 170"), std::string::npos) << w;
    EXPECT_NE(w.find("geometry.mitral_leaflet_length_mm = 8"), std::string::npos) << w;
  }
}

TEST(GeometryRules, AcceptedVariantsBuild) {
  // Random variants around the defaults: whenever the rules accept one, the generator builds
  // it (its own mesh checks included) -- or rejects it only for the fluid box.
  std::mt19937 rng(7);
  auto jitter = [&](double v, double rel) { return v * std::uniform_real_distribution<double>(1 - rel, 1 + rel)(rng); };
  int accepted = 0, built = 0;
  for (int i = 0; i < 20; ++i) {
    Scenario s = default_scenario();
    Geometry& g = s.geometry;
    g.lv_short_axis_mm = jitter(g.lv_short_axis_mm, 0.08);
    g.lv_long_axis_mm = jitter(g.lv_long_axis_mm, 0.06);
    g.lv_volume_ml = jitter(g.lv_volume_ml, 0.12);
    g.la_volume_ml = jitter(g.la_volume_ml, 0.3);
    g.mitral_diameter_mm = jitter(g.mitral_diameter_mm, 0.1);
    g.aortic_diameter_mm = jitter(g.aortic_diameter_mm, 0.1);
    g.mitral_leaflet_length_mm = jitter(g.mitral_leaflet_length_mm, 0.15);
    g.aortic_root_diameter_mm = jitter(g.aortic_root_diameter_mm, 0.1);
    g.pulmonary_vein_diameter_mm = jitter(g.pulmonary_vein_diameter_mm, 0.2);
    g.target_edge_mm = jitter(2.5, 0.3);
    if (!rules(g).empty()) continue;
    ++accepted;
    try {
      geometry::build_left_heart(g, s.fluid);
      ++built;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("fluid.box_"), std::string::npos) << "variant " << i << ": " << e.what();
    }
  }
  std::cout << "rules accepted " << accepted << " of 20 variants, " << built << " built\n";
  EXPECT_GE(accepted, 8);
  EXPECT_GE(built, 6);
}

}  // namespace
}  // namespace systole::config
