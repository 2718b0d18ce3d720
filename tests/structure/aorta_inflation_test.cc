// The aorta alone inflated from its ground pressure (scene::AortaInflation, docs/fsei.md session
// 16): the afterload's stiffness without blood. Measured on this machine (2026-12-02, fsi
// defaults with the aorta's c read in rho U^2, 4312 Pa, the 160 mm box): 60 -> 70 mmHg stores
// 4.77 ml with the wall pre-stressed for all 60 mmHg (0.48 ml/mmHg: the heart's ~0.5), 9.26 ml
// with a quarter of it by the wall (the rest an outer load) and 10.73 ml with the outer load alone.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/rigs/aorta_inflation.h"

namespace systole {
namespace {

config::Scenario aorta_scenario() {
  nlohmann::json doc{{"scene", "fsi"},
                     {"tissue", {{"aorta", {{"fung_c_pa", 4312.0}}}}},
                     {"fluid", {{"box_z_mm", 160.0}}},
                     {"structure", {{"strain_limit", 0.75}}}};
  doc["fsei"]["defaults"] = "seed";  // measured on the table's defaults (2026-12-02)
  return config::parse_scenario(doc);
}

struct Inflation {
  double at_ground_ml, at_70_ml, at_80_ml;
};

Inflation inflate(double share) {
  scene::AortaInflation aorta(aorta_scenario(), 60, share, 0.5);
  Inflation r{};
  const scene::AortaInflationPoint a = aorta.hold(60), b = aorta.hold(70), c = aorta.hold(80);
  EXPECT_TRUE(a.settled && b.settled && c.settled) << share;
  r.at_ground_ml = a.volume_change_ml;
  r.at_70_ml = b.volume_change_ml;
  r.at_80_ml = c.volume_change_ml;
  std::printf("  [measured] share %.2f: dV %.3f ml at 60, %.3f at 70, %.3f at 80 mmHg\n", share, r.at_ground_ml, r.at_70_ml,
              r.at_80_ml);
  return r;
}

// With the outer load alone (share 0) the built aorta is exactly in equilibrium at the ground
// pressure; with a pre-stress it is nearly so (the pre-stress's smoothing leaves a residual: a
// few ml against the lumen's ~110). The smaller the wall's share, the softer the aorta above the
// ground pressure (the Fung law stiffens with the pre-strain), and every wall stiffens as it fills.
TEST(AortaInflation, TheWallsShareOfTheGroundPressureSetsItsCompliance) {
  const Inflation full = inflate(1.0), quarter = inflate(0.25), outer = inflate(0.0);
  EXPECT_LT(std::abs(outer.at_ground_ml), 0.01);
  EXPECT_LT(std::abs(full.at_ground_ml), 5.0);
  EXPECT_LT(std::abs(quarter.at_ground_ml), 5.0);
  auto compliance = [](double a, double b) { return (b - a) / 10.0; };  // ml/mmHg over 10 mmHg
  const double c_full = compliance(full.at_ground_ml, full.at_70_ml);
  const double c_quarter = compliance(quarter.at_ground_ml, quarter.at_70_ml);
  const double c_outer = compliance(outer.at_ground_ml, outer.at_70_ml);
  EXPECT_GT(c_full, 0.0);
  EXPECT_GT(c_quarter, 1.5 * c_full);
  EXPECT_GT(c_outer, c_quarter);
  for (const Inflation& x : {full, quarter})
    EXPECT_LT(compliance(x.at_70_ml, x.at_80_ml), compliance(x.at_ground_ml, x.at_70_ml));
}

TEST(AortaInflation, BadInputNamesTheValue) {
  try {
    scene::AortaInflation aorta(aorta_scenario(), 60, 1.5, 0.5);
    FAIL() << "a share of 1.5 was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("prestress_fraction = 1.5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(scene::AortaInflation(aorta_scenario(), 60, 1.0, 0.0), InputError);
  config::Scenario free_outlet = aorta_scenario();
  free_outlet.fsei.aorta.outlet_held = false;
  EXPECT_THROW(scene::AortaInflation(free_outlet, 60, 1.0, 0.5), InputError);
}

}  // namespace
}  // namespace systole
