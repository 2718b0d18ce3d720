// solver/scene: every advertised metric name is really produced; the analytic scene.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/config/scenario.h"
#include "solver/scene/scene.h"

namespace systole::scene {
namespace {

class Quiet final : public RunControl {
 public:
  void on_progress(const ProgressReport&) override { ++reports; }
  bool cancel_requested() override { return cancel; }
  int reports = 0;
  bool cancel = false;
};

TEST(Scene, AdvertisedMetricsAreProduced) {
  for (const std::string scene : {"lumped", "analytic"}) {
    config::Scenario s = config::parse_scenario({{"scene", scene}});
    Quiet control;
    const RunResult r = run(s, control);
    ASSERT_FALSE(metric_names(scene).empty()) << scene;
    for (const auto& name : metric_names(scene)) EXPECT_TRUE(r.metrics.count(name)) << scene << ": " << name;
    EXPECT_GE(control.reports, 1);
  }
  EXPECT_TRUE(metric_names("fsei").empty());
}

TEST(Scene, AnalyticIshigamiAtKnownPoints) {
  Quiet control;
  // f(pi/2, pi/2, 1) = 1 + a + b.
  const auto s = config::parse_scenario(
      {{"scene", "analytic"}, {"analytic", {{"x1", M_PI / 2}, {"x2", M_PI / 2}, {"x3", 1.0}}}});
  EXPECT_NEAR(run(s, control).metrics.at("f"), 1 + 7 + 0.1, 1e-12);
  control.cancel = true;
  EXPECT_THROW(run(s, control), Cancelled);
}

}  // namespace
}  // namespace systole::scene
