#pragma once
// The tissue electrophysiology (solver/electro) as a coupling::Module.
//
// Contract
// - max_step_ms() = the tissue's fixed time step (its accuracy/stability step, chosen by the
//   scenario). The tissue keeps its own grid of steps t_n = n dt_EP: step(dt) moves the module's
//   clock by dt and takes the tissue steps whose end is within half a step of the clock, so the
//   outputs at clock time t are the tissue's at the grid time nearest t (ours; exact on the grid
//   when the synchronisation step is a multiple of dt_EP, as the scenes choose it).
// - The EP has no inputs from the other modules (no mechano-electric feedback in the seed's
//   model), so re-running an interval gives the same result: save()/restore() keep only the
//   module's clock, and after a restore() the steps up to the tissue's own (further) time are
//   replayed by moving the clock (ours: exact, and strong coupling costs no extra EP work).
// - Outputs: tissue().active_tension_kpa() (Nash–Panfilov, per EP node) and vm_mv(). During a
//   replay they are the tissue's values at its own time, which is the end of the interval being
//   repeated: the value the repeated pass would compute there.
#include <string>

#include "solver/core/state_archive.h"
#include "solver/coupling/module.h"
#include "solver/electro/tissue.h"

namespace systole::coupling {

class ElectroModule final : public Module {
 public:
  explicit ElectroModule(electro::TissueSolver& tissue) : tissue_(tissue), clock_ms_(tissue.time_ms()) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return clock_ms_; }
  double max_step_ms() const override { return tissue_.dt_ms(); }
  void step(double dt_ms) override;
  void save() override { saved_ms_ = clock_ms_; }
  void restore() override { clock_ms_ = saved_ms_; }

  electro::TissueSolver& tissue() { return tissue_; }
  const electro::TissueSolver& tissue() const { return tissue_; }
  long long tissue_steps() const { return tissue_steps_; }
  // Checkpoints: the module's clock (the tissue's state is the tissue's to export).
  void export_state(StateArchive& archive, const std::string& prefix) const {
    archive.put_scalar(prefix + "clock_ms", clock_ms_);
  }
  void import_state(const StateArchive& archive, const std::string& prefix) {
    clock_ms_ = saved_ms_ = archive.scalar(prefix + "clock_ms");
  }

 private:
  std::string name_ = "electro";
  electro::TissueSolver& tissue_;
  double clock_ms_ = 0, saved_ms_ = 0;
  long long tissue_steps_ = 0;
};

}  // namespace systole::coupling
