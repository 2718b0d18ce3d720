#pragma once
// The 0-D circulation (solver/lumped) as a coupling::Module whose LV and/or LA are EXTERNAL
// chambers: their volumes come from 3-D meshes (the electromechanics and FSEI scenes), and the
// circulation returns the chamber pressures that load those meshes.
//
// Contract
// - Input (pressure-driven chambers): set_imposed_pressures(), held over the substeps.
// - Input (volume-driven chambers): set_target_volumes(t_ms, volumes): the external chambers' volumes reached at time
//   t_ms (the 3-D module's clock at the synchronisation point, >= time_ms()). Each substep
//   imposes the volume interpolated linearly in time between the module's state at the moment
//   of the call and that target (ours); past the target time the volume is held.
// - Output: readout() (pressures, volumes, flows at time_ms()).
// - max_step_ms() = lumped.time_step_ms (an accuracy step: classical RK4, whose stability is
//   not the limit at these steps). step() throws what Circulation::advance throws
//   (InstabilityError on a non-finite state or a negative volume).
// - save()/restore(): the Circulation's state by value; the inputs (imposed pressures, target
//   volumes) are kept across restore() (module.h).
#include <optional>
#include <string>

#include "solver/config/scenario.h"
#include "solver/coupling/module.h"
#include "solver/lumped/circulation.h"

namespace systole::coupling {

class LumpedModule final : public Module {
 public:
  // initial: which chambers are external and their volumes at t = 0; pressure_driven: which of
  // them take an imposed pressure instead of an imposed volume (see Circulation).
  LumpedModule(const config::Scenario& scenario, const lumped::ExternalVolumes& initial,
               const lumped::PressureDriven& pressure_driven = {});

  const std::string& name() const override { return name_; }
  double time_ms() const override { return 1000 * circulation_.time_s(); }
  double max_step_ms() const override { return step_ms_; }
  void step(double dt_ms) override;
  void save() override { saved_ = circulation_; }
  void restore() override;

  void set_target_volumes(double t_ms, const lumped::ExternalVolumes& volumes);
  // Pressure-driven chambers: the pressure held over the following substeps.
  void set_imposed_pressures(const lumped::ImposedPressures& p) { circulation_.set_imposed_pressures(p); }
  lumped::Readout readout() const { return circulation_.readout(); }
  const lumped::Circulation& circulation() const { return circulation_; }

 private:
  struct Anchor {
    double start_ms = 0, target_ms = 0;
    lumped::ExternalVolumes start, target;
  };
  lumped::ExternalVolumes volumes_at(double t_ms) const;

  std::string name_ = "lumped";
  lumped::Circulation circulation_;
  double step_ms_;
  Anchor anchor_;
  std::optional<lumped::Circulation> saved_;
};

}  // namespace systole::coupling
