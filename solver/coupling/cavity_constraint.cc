#include "solver/coupling/cavity_constraint.h"

#include <cmath>
#include <string>

#include "solver/core/errors.h"

namespace systole::coupling {

CavityPressureConstraint::CavityPressureConstraint(std::string name, Access access, double initial_pressure_mmhg,
                                                   double initial_slope_ml_per_mmhg)
    : name_(std::move(name)), access_(std::move(access)), pressure_mmhg_(initial_pressure_mmhg),
      slope_(initial_slope_ml_per_mmhg) {
  if (!(initial_slope_ml_per_mmhg > 0) || !std::isfinite(initial_slope_ml_per_mmhg))
    throw InputError(name_ + ": initial slope " + std::to_string(initial_slope_ml_per_mmhg) +
                     " ml/mmHg must be a positive number");
  access_.impose_pressure_mmhg(pressure_mmhg_);
}

void CavityPressureConstraint::update(std::vector<double>& data) {
  const double t = access_.time_ms();
  const double r = access_.mesh_volume_ml() - access_.blood_volume_ml();
  if (!std::isfinite(r))
    throw InstabilityError("coupling", name_, t / 1000, "non-finite chamber volume mismatch");
  if (t != interval_time_ms_) {  // first pass of a new synchronisation interval
    interval_time_ms_ = t;
    have_previous_ = false;
  } else if (have_previous_ && pressure_mmhg_ != previous_pressure_) {
    const double secant = (r - previous_residual_) / (pressure_mmhg_ - previous_pressure_);
    if (secant > 0 && std::isfinite(secant)) slope_ = secant;  // dr/dp > 0 physically (ours: else keep)
  }
  previous_pressure_ = pressure_mmhg_;
  previous_residual_ = r;
  have_previous_ = true;
  last_residual_ml_ = r;
  data.assign(1, pressure_mmhg_ - r / slope_);
}

Transfer CavityPressureConstraint::transfer() {
  Transfer t;
  t.name = name_;
  t.read = [this](std::vector<double>& data) { update(data); };
  t.write = [this](const std::vector<double>& data) {
    pressure_mmhg_ = data.at(0);
    access_.impose_pressure_mmhg(pressure_mmhg_);
  };
  t.relaxed = false;
  return t;
}

}  // namespace systole::coupling
