#pragma once
// Nash–Panfilov active tension (eq 23, Nash & Panfilov 2004, Prog Biophys Mol Biol 85:501):
//   d tau / dt = psi(v) [k_tau v - tau] / t_scale,
// v = (Vm - rest) / (peak - rest) the normalised potential (clamped to [0, 1], ours), psi a
// smooth step from 0.1 while v > v_switch (contraction) to 1 below it (relaxation):
//   psi(v) = 0.1 + 0.9 / (1 + exp((v - v_switch) / width)),  v_switch = 0.05, width = 0.01
// (the smooth form and width are ours; Nash & Panfilov use the sharp step at 0.05).
// t_scale: the model time unit (ours: 12.9 ms, the Aliev–Panfilov unit of Nash & Panfilov),
// so tension rises with time constant 129 ms and relaxes with 12.9 ms. Exact exponential
// integration over a step with psi frozen (unconditionally stable).
// Output: tau per node in kPa (k_tau in kPa), read by the structure module through
// ActiveTension::tension_kpa() (via solver/coupling).
#include <vector>

namespace systole::electro {

struct TensionParams {
  double k_tau_kpa;
  double t_scale_ms;
  double v_switch;
  double width;
};
// The defaults above with the given amplitude.
TensionParams default_tension_params(double k_tau_kpa);

double tension_psi(const TensionParams& p, double v_normalised);

class ActiveTension {
 public:
  ActiveTension(std::size_t nodes, TensionParams params);
  // rest_mv, peak_mv: per node, from each node's cell model.
  void advance(double dt_ms, const std::vector<double>& vm_mv, const std::vector<double>& rest_mv,
               const std::vector<double>& peak_mv);
  const std::vector<double>& tension_kpa() const { return tau_kpa_; }
  // Puts back a state tension_kpa() returned (checkpoints); std::invalid_argument for another
  // node count.
  void restore(std::vector<double> tension_kpa);
  const TensionParams& params() const { return params_; }

 private:
  TensionParams params_;
  std::vector<double> tau_kpa_;
};

}  // namespace systole::electro
