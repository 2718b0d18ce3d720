// Unit tier of the multirate scheduler: sub-cycling, limits, diagnoses, option checks.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/core/errors.h"
#include "solver/coupling/scheduler.h"
#include "toy_modules.h"

namespace systole::coupling {
namespace {

using testing::Oscillator;

// A module whose limit varies in time; it checks every step against its own limit
// independently of the scheduler's statistics.
class VaryingLimit final : public Module {
 public:
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_; }
  double max_step_ms() const override { return 0.1 + 0.05 * std::sin(t_); }
  void step(double dt) override {
    worst_ratio = std::max(worst_ratio, dt / max_step_ms());
    t_ += dt;
    ++steps;
  }
  void save() override { saved_ = t_; }
  void restore() override { t_ = saved_; }
  double worst_ratio = 0;
  long long steps = 0;

 private:
  std::string name_ = "varying";
  double t_ = 0, saved_ = 0;
};

// A module whose stable step halves at every step (a blow-up in the making).
class Collapsing final : public Module {
 public:
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_; }
  double max_step_ms() const override { return limit_; }
  std::string step_limiter() const override { return "cell (1,2,3)"; }
  void step(double dt) override {
    t_ += dt;
    limit_ *= 0.5;
  }
  void save() override {}
  void restore() override {}

 private:
  std::string name_ = "collapsing";
  double t_ = 0, limit_ = 0.1;
};

// Every module and the scheduler at t_ms, and no step above the varying module's own limit.
void expect_landed_within_limits(const Scheduler& scheduler, const VaryingLimit& fast, const Module& slow, double t_ms) {
  EXPECT_NEAR(scheduler.time_ms(), t_ms, 1e-12);
  EXPECT_NEAR(fast.time_ms(), t_ms, 1e-12);
  EXPECT_NEAR(slow.time_ms(), t_ms, 1e-12);
  EXPECT_LE(fast.worst_ratio, 1 + 1e-12);
}

TEST(Scheduler, SubCyclingLandsOnTheEndTimeAndNeverExceedsTheLimit) {
  VaryingLimit fast;
  Oscillator slow("slow", 1, 1, 0, 1, 0.45);  // limit 0.9 ms
  SchedulerOptions options;
  options.sync_step_ms = 0.7;
  Scheduler scheduler({{&fast, {}}, {&slow, {}}}, options);
  scheduler.advance_to(10.3);
  expect_landed_within_limits(scheduler, fast, slow, 10.3);
  EXPECT_LE(scheduler.stats().modules[0].max_step_over_limit, 1 + 1e-12);
  EXPECT_LE(scheduler.stats().modules[1].max_step_over_limit, 1 + 1e-12);
  // 15 intervals (14 of 0.7 ms and one of 0.5 ms); the slow module needs one substep each.
  EXPECT_EQ(scheduler.stats().intervals, 15);
  EXPECT_EQ(slow.steps(), 15);
  // The fast one: at least ceil(0.7 / 0.15) substeps per interval, and no sliver substeps:
  // the remainder is split evenly, so no substep is below half the smallest limit (0.05 ms).
  EXPECT_GE(fast.steps, 15 * 5);
  EXPECT_GT(scheduler.stats().modules[0].min_step_ms, 0.025);
  EXPECT_EQ(scheduler.stats().modules[0].steps, fast.steps);
}

// interval_stage: the intervals follow a stage's stable step, so that stage takes exactly one
// step per interval (and per pass with strong coupling), never above its limit, and the run
// lands on the target; the other stages sub-cycle as before.
TEST(Scheduler, IntervalsFollowingAStagesStepGiveItOneStepPerIntervalAndPass) {
  for (CouplingMode mode : {CouplingMode::loose, CouplingMode::strong}) {
    VaryingLimit fast;                          // limit 0.05–0.15 ms
    Oscillator slow("slow", 1, 1, 0, 1, 0.02);  // limit 0.04 ms: several substeps per interval
    SchedulerOptions options;
    options.sync_step_ms = 0.7;
    options.interval_stage = 0;
    options.mode = mode;
    options.strong_max_iterations = 3;  // no transfers: nothing changes, converged at the 2nd pass
    Scheduler scheduler({{&fast, {}}, {&slow, {}}}, options);
    scheduler.advance_to(10.3);
    expect_landed_within_limits(scheduler, fast, slow, 10.3);
    const SchedulerStats& st = scheduler.stats();
    EXPECT_EQ(st.modules[0].steps, st.passes);
    EXPECT_EQ(st.passes, (mode == CouplingMode::strong ? 2 : 1) * st.intervals);
    // 10.3 ms at 0.05–0.15 ms per interval (fixed intervals of 0.7 ms would be 15)
    EXPECT_GE(st.intervals, 10.3 / 0.15);
    EXPECT_LE(st.intervals, 10.3 / 0.05 + 1);
    EXPECT_GT(slow.steps(), st.passes);  // sub-cycled: ceil(interval / 0.04) >= 2 where the interval > 0.04
    EXPECT_LE(st.modules[1].max_step_over_limit, 1 + 1e-12);
  }
  // Two of the stage's steps per interval: half the intervals, two (or, where the limit fell
  // within the interval, three) steps in each.
  {
    VaryingLimit fast;
    Oscillator slow("slow", 1, 1, 0, 1, 0.02);
    SchedulerOptions options;
    options.sync_step_ms = 0.7;
    options.interval_stage = 0;
    options.interval_stage_steps = 2;
    Scheduler scheduler({{&fast, {}}, {&slow, {}}}, options);
    scheduler.advance_to(10.3);
    expect_landed_within_limits(scheduler, fast, slow, 10.3);
    const SchedulerStats& st = scheduler.stats();
    EXPECT_GE(st.modules[0].steps, 2 * st.intervals);
    EXPECT_LE(st.modules[0].steps, 3 * st.intervals);
    EXPECT_LE(st.intervals, 10.3 / 0.1 + 1);
  }
  Oscillator a("a", 1, 1, 0, 1, 0.1), b("b", 1, 1, 0, 1, 0.1);
  for (int bad : {-2, 2}) {
    SchedulerOptions o;
    o.interval_stage = bad;
    try {
      Scheduler scheduler({{&a, {}}, {&b, {}}}, o);
      FAIL() << "no error for interval_stage = " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("interval_stage = " + std::to_string(bad)), std::string::npos) << e.what();
    }
  }
  SchedulerOptions no_steps;
  no_steps.interval_stage = 0;
  no_steps.interval_stage_steps = 0;
  EXPECT_THROW(Scheduler({{&a, {}}, {&b, {}}}, no_steps), InputError);
}

TEST(Scheduler, AdvancingToTheCurrentTimeDoesNothingAndBackwardsIsAnError) {
  Oscillator a("a", 1, 1, 0, 1, 0.1);
  Scheduler scheduler({{&a, {}}}, SchedulerOptions{});
  scheduler.advance_to(0);
  EXPECT_EQ(a.steps(), 0);
  scheduler.advance_to(1);
  EXPECT_THROW(scheduler.advance_to(0.5), std::invalid_argument);
}

TEST(Scheduler, OptionsOutOfRangeNameTheFieldAndTheRange) {
  Oscillator a("a", 1, 1, 0, 1, 0.1);
  SchedulerOptions bad;
  bad.sync_step_ms = 0;
  try {
    Scheduler scheduler({{&a, {}}}, bad);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("sync_step_ms = 0 is out of range (0, inf)"), std::string::npos) << e.what();
  }
  SchedulerOptions bad_relaxation;
  bad_relaxation.relaxation_factor = 1.5;
  EXPECT_THROW(Scheduler({{&a, {}}}, bad_relaxation), InputError);
  SchedulerOptions bad_iterations;
  bad_iterations.strong_max_iterations = 0;
  EXPECT_THROW(Scheduler({{&a, {}}}, bad_iterations), InputError);
  SchedulerOptions bad_reuse;
  bad_reuse.iqn_reuse_intervals = -1;
  EXPECT_THROW(Scheduler({{&a, {}}}, bad_reuse), InputError);
  SchedulerOptions bad_filter;
  bad_filter.iqn_filter = 1;
  try {
    Scheduler scheduler({{&a, {}}}, bad_filter);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("iqn_filter = 1 is out of range (0, 1)"), std::string::npos) << e.what();
  }
}

TEST(Scheduler, ModulesMustStartAtTheSameTime) {
  Oscillator a("a", 1, 1, 0, 1, 0.1), b("b", 1, 1, 0, 1, 0.1);
  b.step(0.01);
  EXPECT_THROW(Scheduler({{&a, {}}, {&b, {}}}, SchedulerOptions{}), std::invalid_argument);
  EXPECT_THROW(Scheduler({{nullptr, {}}}, SchedulerOptions{}), std::invalid_argument);
}

// The forced instability: steps 8x the reported limit. Velocity Verlet is unstable
// above 2/ω; the module's own energy check stops the run and names it, with the time.
TEST(Scheduler, StepsEightTimesTheLimitAreStoppedByTheModulesDiagnosis) {
  Oscillator structure("toy_structure", 1, 1, 0, 1, 0.5);  // limit = 1/ω
  SchedulerOptions options;
  options.sync_step_ms = 100;
  options.step_limit_factor = 8;
  Scheduler scheduler({{&structure, {}}}, options);
  try {
    scheduler.advance_to(1000);
    FAIL() << "the unstable run was not stopped";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "toy_structure");
    EXPECT_EQ(e.place(), "node 0");
    EXPECT_GT(e.time_s(), 0);
    EXPECT_LT(e.time_s(), 1.0);
  }
  // The same run within the limit is stable and its energy bounded.
  Oscillator stable("toy_structure", 1, 1, 0, 1, 0.5);
  SchedulerOptions within = options;
  within.step_limit_factor = 1;
  Scheduler ok({{&stable, {}}}, within);
  EXPECT_NO_THROW(ok.advance_to(1000));
  EXPECT_LE(std::abs(stable.x()), 1.5);
}

TEST(Scheduler, ACollapsingStableStepIsDiagnosedWithTheModuleName) {
  Collapsing c;
  Scheduler scheduler({{&c, {}}}, SchedulerOptions{});
  try {
    scheduler.advance_to(1);
    FAIL() << "no diagnosis";
  } catch (const InstabilityError& e) {
    EXPECT_EQ(e.module(), "coupling");
    EXPECT_NE(std::string(e.what()).find("module 'collapsing' fell to"), std::string::npos) << e.what();
    EXPECT_EQ(e.place(), "module collapsing, cell (1,2,3)");  // where the module says its step is set
  }
}

// Strong coupling with a single pass per interval is the loose scheme, bit for bit.
TEST(Scheduler, StrongCouplingWithOnePassIsLooseCoupling) {
  auto run = [](CouplingMode mode) {
    Oscillator a("a", 1, 1, 0.5, 1, 0.05), b("b", 2, 1.5, 0.5, 0, 0.05);
    std::vector<Stage> stages{
        {&a, {{.name = "x_a", .read = [&](std::vector<double>& d) { d.assign(1, a.x()); },
               .write = [&](const std::vector<double>& d) { b.partner_ = d[0]; }}}},
        {&b, {{.name = "x_b", .read = [&](std::vector<double>& d) { d.assign(1, b.x()); },
               .write = [&](const std::vector<double>& d) { a.partner_ = d[0]; }}}}};
    SchedulerOptions options;
    options.sync_step_ms = 0.25;
    options.mode = mode;
    options.strong_max_iterations = 1;
    Scheduler scheduler(stages, options);
    scheduler.advance_to(5);
    return std::pair{a.x(), b.x()};
  };
  const auto loose = run(CouplingMode::loose);
  const auto strong = run(CouplingMode::strong);
  EXPECT_EQ(loose.first, strong.first);
  EXPECT_EQ(loose.second, strong.second);
}

}  // namespace
}  // namespace systole::coupling
