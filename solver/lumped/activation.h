#pragma once
// Chamber activation a(t) in [0, 1] and elastance E(t) = Emin + (Emax - Emin) a(t)
// (time-varying elastance, Suga & Sagawa; solver/lumped/README.md "Equations").
#include <vector>

#include "solver/config/scenario.h"

namespace systole::lumped {

// Activation durations scale with sqrt(period / 857.14 ms) (ours, Bazett-like); the same rule
// is checked by config::parse_scenario (the scaled twitch must fit in one period).
double activation_duration_scale(double period_s);

// Timing of one chamber's twitch within the cardiac cycle, all in seconds.
struct ChamberTiming {
  double period_s;
  double onset_s;        // activation onset within each period, in [0, period)
  double contraction_s;  // rise time (already scaled to the heart rate)
  double relaxation_s;   // decay time (already scaled)

  // From the scenario: the LV starts at t = 0 of each beat, the LA av_delay_ms before the next
  // LV onset (t = period - av_delay within each beat).
  static ChamberTiming lv(const config::Scenario& s);
  static ChamberTiming la(const config::Scenario& s);

  // a(t) for any t >= 0 (periodic): raised-cosine rise 0.5 (1 - cos(pi tau / contraction)),
  // then raised-cosine fall 0.5 (1 + cos(pi (tau - contraction) / relaxation)), then 0; tau is
  // the time since the latest onset (ours). C^1, smooth between the breakpoints.
  double activation(double t_s) const;

  // The times in [0, period) where a(t) changes formula (onset, peak, end of relaxation);
  // stepping on them keeps a fixed-step integrator at its full order.
  std::vector<double> breakpoints_s() const;
};

struct Elastance {
  double emin_mmhg_per_ml;
  double emax_mmhg_per_ml;
  ChamberTiming timing;
  double at(double t_s) const {
    return emin_mmhg_per_ml + (emax_mmhg_per_ml - emin_mmhg_per_ml) * timing.activation(t_s);
  }
};

}  // namespace systole::lumped
