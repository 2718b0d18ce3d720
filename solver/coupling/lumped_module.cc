#include "solver/coupling/lumped_module.h"

#include <algorithm>
#include <stdexcept>

namespace systole::coupling {

LumpedModule::LumpedModule(const config::Scenario& scenario, const lumped::ExternalVolumes& initial,
                           const lumped::PressureDriven& pressure_driven)
    : circulation_(scenario, initial, pressure_driven), step_ms_(scenario.lumped.time_step_ms) {
  if (circulation_.lv_external()) anchor_.start.lv_ml = anchor_.target.lv_ml = initial.lv_ml;
  if (circulation_.la_external()) anchor_.start.la_ml = anchor_.target.la_ml = initial.la_ml;
}

void LumpedModule::set_target_volumes(double t_ms, const lumped::ExternalVolumes& volumes) {
  if (circulation_.lv_external() != volumes.lv_ml.has_value() ||
      circulation_.la_external() != volumes.la_ml.has_value())
    throw std::invalid_argument(
        "LumpedModule::set_target_volumes: give a volume for exactly the volume-driven chambers");
  const lumped::Readout now = circulation_.readout();
  anchor_.start_ms = time_ms();
  anchor_.target_ms = std::max(t_ms, anchor_.start_ms);
  anchor_.start = {};
  if (volumes.lv_ml) anchor_.start.lv_ml = now.lv_volume_ml;
  if (volumes.la_ml) anchor_.start.la_ml = now.la_volume_ml;
  anchor_.target = volumes;
}

lumped::ExternalVolumes LumpedModule::volumes_at(double t_ms) const {
  const double span = anchor_.target_ms - anchor_.start_ms;
  const double w = span > 0 ? std::clamp((t_ms - anchor_.start_ms) / span, 0.0, 1.0) : 1.0;
  lumped::ExternalVolumes v;
  if (anchor_.target.lv_ml) v.lv_ml = *anchor_.start.lv_ml + w * (*anchor_.target.lv_ml - *anchor_.start.lv_ml);
  if (anchor_.target.la_ml) v.la_ml = *anchor_.start.la_ml + w * (*anchor_.target.la_ml - *anchor_.start.la_ml);
  return v;
}

void LumpedModule::step(double dt_ms) {
  circulation_.advance(dt_ms / 1000, volumes_at(time_ms() + dt_ms));
}

void LumpedModule::restore() {
  if (!saved_) throw std::logic_error("LumpedModule::restore without save");
  const lumped::ImposedPressures inputs = circulation_.imposed_pressures();
  circulation_ = *saved_;
  circulation_.set_imposed_pressures(inputs);
}

}  // namespace systole::coupling
