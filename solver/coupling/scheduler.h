#pragma once
// The multirate scheduler: every module advances at its own step between synchronisation
// points, where the scene's transfers carry data between modules (MODEL.md §7, seed Fig. 6).
//
// One synchronisation interval [t, t + Δt_sync] reads like Fig. 6:
//   for each stage, in order (e.g. EP, fluid, then the structure with the new loads):
//     sub-cycle the stage's module from t to t + Δt_sync, each substep
//       dt = min(max_step_ms(), time left)                         (multirate, ours)
//     run the stage's transfers (outputs of this module -> inputs of later stages now, and of
//       earlier stages at the next interval or the next strong-coupling iteration)
//   loose coupling: done (one pass, as the seed's production runs);
//   strong coupling: restore every module to t and repeat the pass, the transferred data
//     relaxed (constant factor, Aitken's Δ² or interface quasi-Newton IQN-ILS), until the relative change of all transferred
//     data between two passes is below the tolerance (the seed: 1e-4) or the iteration limit
//     is reached (counted and reported, never hidden).
//
// Transferred data are flat vectors of doubles (a pressure, a volume, nodal forces, nodal
// tensions): the scheduler relaxes and measures them without knowing what they are. Within an
// interval a module sees its inputs held constant (ours; the seed's loose scheme does the same).
#include <chrono>
#include <functional>
#include <string>
#include <vector>

#include "solver/core/state_archive.h"
#include "solver/coupling/module.h"

namespace systole::coupling {

// Moves one output of a module into the inputs of others.
struct Transfer {
  std::string name;
  // Fills `data` from the source module's current outputs (resize as needed).
  std::function<void(std::vector<double>& data)> read;
  // Hands (possibly relaxed) data to the target module(s).
  std::function<void(const std::vector<double>& data)> write;
  // Strong coupling: relax these data between passes (false: write each pass's data as read;
  // still part of the convergence measure). Relax one interface quantity of a loop, typically
  // the loads on the structure.
  bool relaxed = true;
};

struct Stage {
  Module* module = nullptr;        // not owned; outlives the scheduler
  std::vector<Transfer> after;     // run after the module reached the synchronisation point
};

enum class CouplingMode { loose, strong };
enum class Relaxation { none, constant, aitken, iqn_ils };
enum class FirstPassPredictor { last, linear };

struct SchedulerOptions {
  double sync_step_ms = 1.0;              // Δt_sync, > 0
  // >= 0 (ours): the intervals follow that stage's stable step: each is at most the stage's
  // max_step_ms() at its start (and at most sync_step_ms), the time to the target split evenly,
  // so the stage takes one step per interval and pass (the coupling at the fluid's own CFL step
  // instead of a fixed Δt_sync that the fluid fills with one or two steps). -1: fixed intervals.
  int interval_stage = -1;
  // With interval_stage >= 0: an interval is at most this many of the stage's stable steps (>= 1).
  int interval_stage_steps = 1;
  CouplingMode mode = CouplingMode::loose;
  double strong_tolerance = 1e-4;         // relative change of the transferred data
  int strong_max_iterations = 4;          // passes per interval, >= 1
  Relaxation relaxation = Relaxation::aitken;  // strong coupling only
  double relaxation_factor = 0.5;         // constant factor / Aitken's and IQN-ILS's first factor, (0, 1]
  // IQN-ILS: the secant columns of this many earlier intervals are reused (0: this interval's
  // only), and a column whose part orthogonal to the newer ones is below iqn_filter times its
  // norm is dropped (ours: Haelterman et al. 2016's QR2 filter).
  int iqn_reuse_intervals = 8;
  double iqn_filter = 1e-2;
  // Strong coupling (ours): the first pass of an interval already measures the relaxed
  // transfers' change, against the data last written (the previous interval's final data), so
  // an interval whose first pass changes them less than strong_tolerance ends after that pass.
  // Only meaningful when every relaxed transfer is consumed before it is produced in a pass (the
  // structure before the fluid, relaxing the loads): the first pass then evaluates the coupled
  // map at the previous interval's data, and a small change is a small fixed-point residual.
  // The data last written by the relaxed transfers are part of the checkpoint (export_state),
  // and import_state writes them again, so a resumed run takes the same passes.
  bool first_pass_residual = false;
  // With first_pass_residual (ours): what the relaxed transfers write before an interval's first
  // pass. last: the data last written (the loads lag one interval: the one-pass intervals are
  // explicit coupling, whose lag can pump a slow oscillation that changes the data by less than
  // the tolerance per interval). linear: extrapolated from the last two intervals' final data,
  //   x* = x_n + (h_{n+1} / h_n) (x_n − x_{n−1}),
  // so the first pass starts from a second-order guess of the interval's loads and its residual
  // measures the guess. Explicit coupling with this guess is stable for an added-mass ratio below
  // 1/3 only (against 1 for last): the first-pass check and the further passes must catch such
  // modes (tests/coupling/coupling_verification_test.cc).
  FirstPassPredictor first_pass_predictor = FirstPassPredictor::last;
  // The smallest step a module may report before the run is declared unstable (a collapsing
  // stable step means a blow-up in the making) (ours).
  double min_step_ms = 1e-9;
  // Test hook: substeps of min(factor * max_step_ms(), time left). Only tests and the
  // stability study set it above 1 (to show a module detects its own blow-up).
  double step_limit_factor = 1.0;
};
// Throws InputError naming the option and the allowed range.
void validate(const SchedulerOptions& options);

struct ModuleStats {
  std::string name;
  long long steps = 0;
  double min_step_ms = 0, max_step_ms = 0;  // over all substeps taken
  double max_step_over_limit = 0;           // max of dt / max_step_ms() (<= 1 unless a test scales)
  double wall_time_s = 0;
};

struct SchedulerStats {
  std::vector<ModuleStats> modules;     // in stage order
  long long intervals = 0;
  long long passes = 0;                 // stage passes (= intervals for loose coupling)
  long long unconverged_intervals = 0;  // strong coupling hit strong_max_iterations
  double max_final_residual = 0;        // largest relative change at the end of an interval
};

class Scheduler {
 public:
  // Valid from construction: options validated, every stage has a module, all modules at the
  // same time (InputError / std::invalid_argument otherwise).
  Scheduler(std::vector<Stage> stages, SchedulerOptions options);

  double time_ms() const { return time_ms_; }
  // Advances every module to t_ms (>= time_ms()) in synchronisation intervals of
  // sync_step_ms (the last one shortened to land on t_ms; or following interval_stage's step,
  // above). Throws what the modules throw
  // (InstabilityError names the module), and InstabilityError("coupling", ...) when a module's
  // reported step falls below min_step_ms or is not finite.
  void advance_to(double t_ms);

  const SchedulerStats& stats() const { return stats_; }
  // Checkpoints (between intervals): the clock and the statistics under `prefix`. The modules'
  // own states are the scene's to save; import_state() expects every module already restored
  // to the exported time (std::invalid_argument otherwise; InputError for a missing entry or
  // another stage count).
  void export_state(StateArchive& archive, const std::string& prefix) const;
  void import_state(const StateArchive& archive, const std::string& prefix);

 private:
  double run_pass(double t_end_ms, int iteration);
  void sub_cycle(std::size_t stage, double t_end_ms);
  double relax(std::size_t transfer, bool relaxed_transfer, int iteration);
  // first_pass_predictor = linear: writes the relaxed transfers' extrapolated data for the
  // interval of length interval_ms about to start.
  void predict(double interval_ms);
  // IQN-ILS's update of transfer k's data x from the raw data and residual r of this pass.
  void quasi_newton(std::size_t k, const std::vector<double>& raw, const std::vector<double>& r, int iteration);

  std::vector<Stage> stages_;
  SchedulerOptions options_;
  double time_ms_ = 0;
  SchedulerStats stats_;
  // Strong coupling, per transfer: raw data of this pass, relaxed data of the previous pass,
  // previous residual (Aitken).
  std::vector<std::vector<double>> current_, previous_, previous_residual_;
  std::vector<double> aitken_;  // Aitken's factor per transfer
  // first_pass_predictor = linear, per transfer: the final data of the interval before the last
  // (x_{n−1}), and the last interval's length h_n (0: none yet)
  std::vector<std::vector<double>> written_before_;
  double last_interval_ms_ = 0;
  // IQN-ILS per transfer: raw data of the last pass; secant columns (Δr, Δx̃) of this interval
  // and of earlier ones, newest first.
  struct SecantColumns {
    std::vector<std::vector<double>> residual_differences, raw_differences;
  };
  struct QuasiNewtonMemory {
    std::vector<double> last_raw;
    SecantColumns current;
    std::vector<SecantColumns> earlier;  // newest interval first, at most iqn_reuse_intervals
  };
  std::vector<QuasiNewtonMemory> iqn_;
};

}  // namespace systole::coupling
