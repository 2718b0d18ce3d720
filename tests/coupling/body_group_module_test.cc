// coupling::BodyGroupModule (the fsi/fsei scenes' structure stage): its limit is the group's
// stable step, a step is one substep of every body, and restore() returns every body to the
// saved instant so that a repeated interval is bitwise the same (strong coupling's contract).
#include <gtest/gtest.h>

#include <vector>

#include "solver/coupling/body_group_module.h"
#include "solver/structure/contact.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::coupling {
namespace {

using structure::Vec3;

// Two stretched membrane spheres side by side (ours: small, fast, with contact enabled).
structure::BodyGroup two_spheres() {
  structure::ShellMaterials m;
  for (auto& t : m.tissue) t = {0.2, 10, 10};
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  structure::ShellOptions o;
  o.law = "fung";
  o.bending = false;
  std::vector<structure::ShellModel> bodies;
  for (double x : {0.0, 12.0}) {
    auto mesh = structure::icosphere(5, 2, 1, geometry::Tissue::kLvMyocardium, false);
    for (auto& p : mesh.position_mm) p += Vec3(x, 0, 0);
    bodies.emplace_back(mesh, m, o);
    std::vector<Vec3> stretched = bodies.back().positions_mm();
    for (auto& p : stretched) p = Vec3(x, 0, 0) + 1.05 * (p - Vec3(x, 0, 0));
    bodies.back().set_state(stretched, std::vector<Vec3>(stretched.size(), Vec3::Zero()));
  }
  return structure::BodyGroup(std::move(bodies), structure::ContactOptions{});
}

TEST(BodyGroupModule, StepsAtTheGroupsLimitAndRestoreRepeatsAnIntervalBitwise) {
  structure::BodyGroup group = two_spheres();
  BodyGroupModule module(group);
  EXPECT_EQ(module.name(), "structure");
  EXPECT_DOUBLE_EQ(module.max_step_ms(), group.stable_step_ms());
  EXPECT_GT(module.max_step_ms(), 0);
  const double dt = 0.5 * module.max_step_ms();
  module.step(dt);
  EXPECT_DOUBLE_EQ(module.time_ms(), dt);
  EXPECT_DOUBLE_EQ(group.body(1).time_ms(), dt);

  module.save();
  for (int i = 0; i < 20; ++i) module.step(dt);
  const std::vector<Vec3> x0 = group.body(0).positions_mm(), x1 = group.body(1).positions_mm();
  const std::vector<Vec3> v1 = group.body(1).velocities_mm_per_ms();
  EXPECT_GT((x0[0] - two_spheres().body(0).positions_mm()[0]).norm(), 0);  // it moved
  module.restore();
  EXPECT_DOUBLE_EQ(module.time_ms(), dt);
  for (int i = 0; i < 20; ++i) module.step(dt);
  for (std::size_t n = 0; n < x0.size(); ++n) {
    EXPECT_EQ(group.body(0).positions_mm()[n], x0[n]) << n;
    EXPECT_EQ(group.body(1).positions_mm()[n], x1[n]) << n;
    EXPECT_EQ(group.body(1).velocities_mm_per_ms()[n], v1[n]) << n;
  }
}

}  // namespace
}  // namespace systole::coupling
