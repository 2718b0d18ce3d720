#pragma once
// Single-cell pacing protocol and AP biomarkers (used by tests, bench and docs/electro.md).
// The cell is paced with a square stimulus (amplitude uA/uF, i.e. uA/cm^2 at C_m = 1) at
// t = k * period; Vm is integrated by forward Euler with the model's Rush–Larsen state update.
// Biomarkers are measured on the LAST beat:
//   rest_mv: Vm just before the last stimulus; peak_mv: max Vm; dvdt_max_v_per_s: max dVm/dt
//   (mV/ms = V/s); apd50_ms / apd90_ms: from the instant of max dVm/dt to the downward
//   crossing of rest + 0.5 / 0.1 (peak - rest), linearly interpolated.
#include <string>
#include <utility>
#include <vector>

namespace systole::electro {

struct PacingProtocol {
  double period_ms;
  int beats;
  double dt_ms;
  double stimulus_ua_per_uf;
  double stimulus_ms;
};

struct ApBiomarkers {
  double rest_mv, peak_mv, dvdt_max_v_per_s, apd50_ms, apd90_ms;
  std::vector<double> last_beat_vm_mv;  // sampled every dt over the last beat
};

ApBiomarkers pace_single_cell(const std::string& model, const PacingProtocol& protocol);
// The same with model parameters overridden by name first (CellModel::set_parameter; an unknown
// name is an InputError).
ApBiomarkers pace_single_cell(const std::string& model, const PacingProtocol& protocol,
                              const std::vector<std::pair<std::string, double>>& parameters);

}  // namespace systole::electro
