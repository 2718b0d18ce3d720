#pragma once
// Beat metrics from sampled curves of ONE beat: physics-free, shared by the 0-D circulation
// (solver/lumped) and the 3-D scenes. Inputs are plain arrays; nothing here knows a model.
//
// Conventions (documented in solver/diagnostics/README.md):
//  - a beat is the window [beat_start_s, beat_start_s + period_s]; phase = (t - beat_start) / T;
//  - flows are positive forward: mitral LA -> LV, aortic LV -> aorta;
//  - end-diastole is the mitral valve closure (or the beat's first sample, with
//    end_diastole_at_beat_start), end-systole the aortic valve closure (the
//    first of each in the beat): EDV, EDP, ESV, ESP are the LV volume and pressure there,
//    interpolated. If the beat has no such closure, EDV/ESV fall back to the largest/smallest
//    LV volume (and the pressure at that sample). Not simply max/min: with leaky closed valves
//    the volume creeps during the isovolumic phases, and the "largest volume" would sit at the
//    end of isovolumic contraction with a systolic pressure as "EDP" (ours);
//  - valve events are crossings of the flow through a threshold (default 0: sign changes),
//    located by linear interpolation between samples.
#include <map>
#include <optional>
#include <span>
#include <string>

namespace systole::diagnostics {

// One beat of samples. All spans have the same length (>= 2); time_s strictly increasing.
struct BeatSamples {
  std::span<const double> time_s;
  std::span<const double> lv_volume_ml;
  std::span<const double> lv_pressure_mmhg;
  std::span<const double> aortic_pressure_mmhg;
  std::span<const double> mitral_flow_ml_s;  // + : LA -> LV
  std::span<const double> aortic_flow_ml_s;  // + : LV -> aorta
  double beat_start_s = 0;
  double period_s = 0;
  // A valve is "open" while its flow exceeds threshold_fraction * (peak |flow| of that valve
  // over the beat). 0 = sign changes (right for 0-D curves); noisy 3-D curves may want ~0.01.
  double valve_threshold_fraction = 0;
  // A crossing counts as a valve event only if the flow then stays on its new side of the
  // level for valve_min_dwell_fraction * period_s (or to the window's end) (ours): a 3-D valve
  // flow ripples through the level for a few ms around an opening (a coupled run's mitral "opened"
  // at 0.386 T and "closed" at 0.388 T; BeatMetrics.ADwellIgnoresARippleThroughTheThreshold).
  // 0 = every crossing counts.
  double valve_min_dwell_fraction = 0;
  // true: end-diastole is the beat's first sample (EDV, EDP there) instead of the mitral
  // closure, for beats that start at the activation with the valves closed (scenes fsi/fsei).
  bool end_diastole_at_beat_start = false;
};

// Phases t/T in [0, 1] of the first opening (upward crossing) and the first closing
// (downward crossing) found in the beat; empty when the flow does not cross. The event away from
// the state of the beat's first sample comes first, the other one is the first crossing back
// after it: a valve that starts closed can only close after it opened.
struct ValveEvents {
  std::optional<double> open_phase;
  std::optional<double> close_phase;
};

struct BeatMetrics {
  double heart_rate_bpm = 0;
  double edv_ml = 0;
  double esv_ml = 0;
  double stroke_volume_ml = 0;                // EDV - ESV
  double ejection_fraction_percent = 0;       // 100 * SV / EDV
  double cardiac_output_l_min = 0;            // SV * HR
  double aortic_forward_volume_ml = 0;        // integral of aortic flow over the beat
  double mitral_inflow_volume_ml = 0;         // integral of mitral flow over the beat
  double lv_end_diastolic_pressure_mmhg = 0;  // LV pressure at end-diastole
  double lv_end_systolic_pressure_mmhg = 0;   // LV pressure at end-systole
  double lv_peak_pressure_mmhg = 0;
  double lv_peak_pressure_phase = 0;
  double aortic_pressure_max_mmhg = 0;
  double aortic_pressure_min_mmhg = 0;
  double aortic_pressure_mean_mmhg = 0;  // time average over the beat (trapezoid rule)
  double mitral_peak_flow_ml_s = 0;
  double aortic_peak_flow_ml_s = 0;
  ValveEvents aortic_valve;
  ValveEvents mitral_valve;
  // Early (E) and atrial (A) filling waves: the first local maximum of the mitral flow after its
  // opening that exceeds 10 % of the beat's peak mitral flow and stands out by as much (its
  // topographic prominence, so ripples on a wave's flank are not waves), and the largest such
  // maximum after it; A is empty when there is only one such maximum.
  std::optional<double> mitral_e_peak_phase, mitral_e_peak_flow_ml_s;
  std::optional<double> mitral_a_peak_phase, mitral_a_peak_flow_ml_s;
};

// Computes every metric above. Throws std::invalid_argument on mismatched or too short
// arrays, non-increasing time, or period_s <= 0.
BeatMetrics compute_beat_metrics(const BeatSamples& beat);

// Flat map with units in the keys (e.g. "edv_ml", "aortic_valve_close_phase",
// "mitral_e_to_a_ratio"); events that did not happen are left out, never NaN.
std::map<std::string, double> to_map(const BeatMetrics& m);

// --- building blocks (also used by the 3-D scenes) --------------------------------------
double stroke_volume_ml(double edv_ml, double esv_ml);
double ejection_fraction_percent(double edv_ml, double esv_ml);  // 0 when edv_ml <= 0
double cardiac_output_l_min(double stroke_volume_ml, double heart_rate_bpm);

// Trapezoid integral of values over time_s, and the time average over [time_s.front(), back()].
double integrate(std::span<const double> time_s, std::span<const double> values);
double time_average(std::span<const double> time_s, std::span<const double> values);

// Linear interpolation of values at time t (clamped to the first/last sample outside).
double value_at(std::span<const double> time_s, std::span<const double> values, double t);

enum class Crossing { kUpward, kDownward };
// Time of the first crossing of `level` in the given direction (linear interpolation), or
// empty. Upward: values[i] <= level < values[i+1]; downward: values[i] > level >= values[i+1].
std::optional<double> first_crossing(std::span<const double> time_s, std::span<const double> values,
                                     double level, Crossing direction);

// As first_crossing, but the first crossing after which the values stay on the new side of
// `level` (upward: > level; downward: <= level) for at least min_dwell_s, or up to the last
// sample if fewer remain. min_dwell_s = 0 is first_crossing.
std::optional<double> first_lasting_crossing(std::span<const double> time_s, std::span<const double> values,
                                             double level, Crossing direction, double min_dwell_s);

// Opening/closing phases of one valve from its flow curve (see ValveEvents): lasting crossings
// of threshold_fraction * peak |flow| (dwell min_dwell_fraction * period_s), the first one away
// from the state of the first sample, then the first one back after it.
ValveEvents valve_events(std::span<const double> time_s, std::span<const double> flow_ml_s,
                         double beat_start_s, double period_s, double threshold_fraction = 0,
                         double min_dwell_fraction = 0);

}  // namespace systole::diagnostics
