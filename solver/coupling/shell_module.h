#pragma once
// A structure::ShellModel (one thin-shell body) as a coupling::Module.
//
// Contract
// - max_step_ms() = the shell's reported stable step at its current state (it stiffens with
//   strain: the scheduler asks again before every substep). step(dt) = one velocity-Verlet
//   substep (ShellModel::substep, which throws InstabilityError naming the body, the node and the
//   time on a blow-up).
// - Inputs (held over the substeps): the cavity pressure and the per-node active tension, set
//   on model() by the scene's transfers.
// - save()/restore(): positions, velocities and the clock by value (the inputs are kept).
#include <string>
#include <vector>

#include "solver/coupling/module.h"
#include "solver/structure/shell.h"

namespace systole::coupling {

class ShellModule final : public Module {
 public:
  // The model must outlive the module.
  explicit ShellModule(structure::ShellModel& model) : name_("structure:" + model.name()), model_(model) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return model_.time_ms(); }
  double max_step_ms() const override { return model_.stable_step_ms(); }
  void step(double dt_ms) override { model_.substep(dt_ms); }
  void save() override;
  void restore() override;

  structure::ShellModel& model() { return model_; }
  const structure::ShellModel& model() const { return model_; }

 private:
  std::string name_;
  structure::ShellModel& model_;
  std::vector<structure::Vec3> saved_x_, saved_v_;
  double saved_t_ = 0;
};

}  // namespace systole::coupling
