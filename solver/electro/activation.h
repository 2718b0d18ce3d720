#pragma once
// Activation and repolarisation times per node, from the potential after each time step.
// - activation: the first upward crossing of threshold_mv since the last reset(), linearly
//   interpolated in time between the two steps;
// - repolarisation: the first later downward crossing of rest + 0.1 (peak - rest), peak being
//   the highest potential seen since activation (90 % repolarisation), interpolated likewise;
// - APD (APD90) = repolarisation - activation.
// Times not reached are NaN. reset() starts a new beat (the scene calls it at each beat start).
#include <vector>

namespace systole::electro {

class ActivationTracker {
 public:
  // resting_mv: per node resting potential of its cell model.
  ActivationTracker(std::vector<double> resting_mv, double threshold_mv);
  // Feed the potentials before (v_old at t_old) and after (v_new at t_new) a step.
  void update(double t_old_ms, const std::vector<double>& v_old, double t_new_ms, const std::vector<double>& v_new);
  void reset();
  const std::vector<double>& activation_ms() const { return activation_ms_; }
  const std::vector<double>& repolarisation_ms() const { return repol_ms_; }
  std::vector<double> apd_ms() const;
  double threshold_mv() const { return threshold_mv_; }
  // The tracker's evolving state (checkpoints): the peaks so far besides the two time arrays.
  const std::vector<double>& peak_mv() const { return peak_mv_; }
  // Puts back what activation_ms(), repolarisation_ms() and peak_mv() returned; throws
  // std::invalid_argument for arrays of another node count.
  void restore(std::vector<double> activation_ms, std::vector<double> repolarisation_ms, std::vector<double> peak_mv);

 private:
  std::vector<double> rest_mv_;
  double threshold_mv_;
  std::vector<double> activation_ms_, repol_ms_, peak_mv_;
};

}  // namespace systole::electro
