#include "solver/coupling/shell_module.h"

namespace systole::coupling {

void ShellModule::save() {
  saved_x_ = model_.positions_mm();
  saved_v_ = model_.velocities_mm_per_ms();
  saved_t_ = model_.time_ms();
}

void ShellModule::restore() {
  model_.set_state(saved_x_, saved_v_);  // recomputes the forces with the latest inputs
  model_.set_time_ms(saved_t_);
}

}  // namespace systole::coupling
