#pragma once
// The 0-D scene driver: beat after beat of the closed-loop circulation until the periodic
// state or scenario.beats (solver/lumped/README.md "Driver").
#include <functional>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/lumped/circulation.h"

namespace systole::lumped {

// Runs the healthy-or-not left heart of `scenario` (every lumped.* field, heart_rate_bpm,
// av_delay_ms, beats, periodicity_tolerance, outputs.*).
//  - Stops after the first beat n >= 2 whose |EDV_n - EDV_{n-1}| / EDV_{n-1} is below
//    periodicity_tolerance (> 0), else after `beats` beats.
//  - on_beat (optional) is called after every beat with the simulated time, the beat number
//    and that beat's metrics.
//  - cancel_requested (optional) is polled before every beat; when it returns true the run
//    stops and returns normally what it has, with metrics["cancelled"] = 1 (0 otherwise).
//    No exception: a cancelled run is an outcome, not an error.
//  - metrics: the last completed beat's metrics (diagnostics::to_map) plus heart_rate_bpm,
//    beats_simulated, periodic (1/0), edv_relative_change, cancelled. No wall_time_s.
//  - beats: per-beat metrics (when outputs.metrics), each with "beat", "beat_start_s" and
//    "edv_relative_change" (beat 1: relative to the initial LV volume).
//  - series (when outputs.time_series): time_s, lv_pressure_mmhg, lv_volume_ml,
//    la_pressure_mmhg, la_volume_ml, aortic_pressure_mmhg, mitral_flow_ml_s, aortic_flow_ml_s,
//    every outputs.time_series_interval_ms over the last outputs.time_series_last_beats beats
//    (0: all), linearly interpolated between integrator steps.
// Throws InstabilityError if the integration blows up (never returns NaN).
RunResult simulate(const config::Scenario& scenario,
                   const std::function<void(const ProgressReport&)>& on_beat = {},
                   const std::function<bool()>& cancel_requested = {});

// Step ends within one beat, from 0 to the period: uniform steps no longer than max_dt_s
// between consecutive activation breakpoints of `circulation`, so no step straddles a change
// of formula of a(t) (RK4 then keeps its fourth order). Every beat reuses the same grid.
std::vector<double> beat_step_grid_s(const Circulation& circulation, double max_dt_s);

}  // namespace systole::lumped
