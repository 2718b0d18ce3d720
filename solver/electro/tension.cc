#include "solver/electro/tension.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace systole::electro {

TensionParams default_tension_params(double k_tau_kpa) { return {k_tau_kpa, 12.9, 0.05, 0.01}; }

double tension_psi(const TensionParams& p, double v) {
  return 0.1 + 0.9 / (1.0 + std::exp((v - p.v_switch) / p.width));
}

ActiveTension::ActiveTension(std::size_t nodes, TensionParams params) : params_(params), tau_kpa_(nodes, 0.0) {}

void ActiveTension::restore(std::vector<double> tension_kpa) {
  if (tension_kpa.size() != tau_kpa_.size())
    throw std::invalid_argument("ActiveTension::restore: " + std::to_string(tension_kpa.size()) + " values for " +
                                std::to_string(tau_kpa_.size()) + " nodes");
  tau_kpa_ = std::move(tension_kpa);
}

void ActiveTension::advance(double dt_ms, const std::vector<double>& vm, const std::vector<double>& rest,
                            const std::vector<double>& peak) {
  for (std::size_t i = 0; i < tau_kpa_.size(); ++i) {
    const double v = std::clamp((vm[i] - rest[i]) / (peak[i] - rest[i]), 0.0, 1.0);
    const double rate = tension_psi(params_, v) / params_.t_scale_ms;
    const double target = params_.k_tau_kpa * v;
    tau_kpa_[i] = target + (tau_kpa_[i] - target) * std::exp(-rate * dt_ms);
  }
}

}  // namespace systole::electro
