#include "solver/coupling/electro_module.h"

#include <stdexcept>

namespace systole::coupling {

void ElectroModule::step(double dt_ms) {
  if (!(dt_ms > 0)) throw std::logic_error("ElectroModule::step: dt must be > 0, got " + std::to_string(dt_ms));
  clock_ms_ += dt_ms;
  // The tissue keeps its own fixed-step grid: it steps while it is more than half a step behind
  // the clock (a replay after restore() finds it ahead and takes no step).
  while (tissue_.time_ms() < clock_ms_ - 0.5 * tissue_.dt_ms()) {
    tissue_.step();
    ++tissue_steps_;
  }
}

}  // namespace systole::coupling
