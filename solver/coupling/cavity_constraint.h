#pragma once
// The cavity pressure of a 3-D chamber whose blood volume is the 0-D circulation's state: the
// iterated volume constraint of the electromechanics scene (issue #8; the choice and its
// justification: solver/coupling/README.md "Chamber pressure").
//
// The wall (structure) and the 0-D chamber (lumped, pressure-driven) both take the same cavity
// pressure p over a synchronisation interval. At the end of a pass the constraint measures
//   r(p) = V_mesh(p) − V_blood(p)   [ml]
// and sets the next pressure by a secant (Newton) step p ← p − r / S, with
//   S ≈ dr/dp = C_wall + Δt (G_in + G_out) > 0
// (a stiffer wall or closed valves make S small, never negative). S starts from the previous
// interval's estimate (initial_slope before any) and is updated from the passes of the interval.
// With strong coupling the passes repeat until p stops changing: V_mesh = V_blood at every
// synchronisation point, through the isovolumic phases too (both valves closed: the blood volume
// is frozen and the wall must hold it, whatever the pressure). With loose coupling one Newton
// correction per interval keeps the mismatch bounded instead of exact.
#include <functional>
#include <string>

#include "solver/coupling/scheduler.h"

namespace systole::coupling {

class CavityPressureConstraint {
 public:
  struct Access {
    std::function<double()> mesh_volume_ml;              // the wall's cavity volume now
    std::function<double()> blood_volume_ml;             // the 0-D chamber's volume now
    std::function<double()> time_ms;                     // the clock of the synchronisation point
    std::function<void(double)> impose_pressure_mmhg;    // on the wall and on the 0-D chamber
  };
  // Imposes initial_pressure_mmhg at once. initial_slope_ml_per_mmhg > 0 (InputError otherwise).
  CavityPressureConstraint(std::string name, Access access, double initial_pressure_mmhg,
                           double initial_slope_ml_per_mmhg);

  // The transfer to put after the LAST stage that changes either volume (data: {p}; not relaxed:
  // the secant step is the update). The constraint must outlive the scheduler.
  Transfer transfer();

  double pressure_mmhg() const { return pressure_mmhg_; }
  double last_mismatch_ml() const { return last_residual_ml_; }
  double slope_ml_per_mmhg() const { return slope_; }

 private:
  void update(std::vector<double>& data);

  std::string name_;
  Access access_;
  double pressure_mmhg_, slope_;
  double interval_time_ms_ = -1e300;
  bool have_previous_ = false;
  double previous_pressure_ = 0, previous_residual_ = 0, last_residual_ml_ = 0;
};

}  // namespace systole::coupling
