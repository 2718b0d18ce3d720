#pragma once
// The closed-loop 0-D left heart (solver/lumped/README.md):
//
//   pulmonary veins (C_pv) --R_pv--> LA --mitral--> LV --aortic--> Zc --> [C || R_s] --> C_pv
//
// State: LV and LA volumes, the stressed volumes of the systemic compliance C and of the
// pulmonary venous compliance C_pv, and, for valves with inertance, the valve flows.
// Each chamber is either an elastance chamber, P = E(t) (V - V0), or EXTERNAL: its volume is
// imposed by the caller each step (a 3-D chamber) and the circulation returns the chamber
// pressure (the load the caller applies) and the valve flows.
#include <array>
#include <optional>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/lumped/activation.h"
#include "solver/lumped/valve.h"

namespace systole::lumped {

// Volumes of the chambers driven by the caller; a chamber not set here is an elastance
// chamber. Passed to the constructor (which chambers are external, their volumes at t = 0)
// and to every advance() (their volumes at the end of the step).
struct ExternalVolumes {
  std::optional<double> lv_ml;
  std::optional<double> la_ml;
};

// Chambers whose PRESSURE the caller imposes (the 3-D chamber's cavity pressure, solved by the
// caller so that the mesh volume matches the blood volume: coupling/cavity_constraint.h). Their
// volume is a state driven by the valve flows, starting from the ExternalVolumes value given to
// the constructor; the pressure is held over each step (set_imposed_pressures). A chamber is
// driven by volume OR by pressure, not both.
struct PressureDriven {
  bool lv = false;
  bool la = false;
};
struct ImposedPressures {
  double lv_mmhg = 0;
  double la_mmhg = 0;
};

// Everything observable at one instant; all finite.
struct Readout {
  double time_s = 0;
  double lv_volume_ml = 0, la_volume_ml = 0;
  double lv_pressure_mmhg = 0, la_pressure_mmhg = 0;
  double aortic_pressure_mmhg = 0;             // aortic root, upstream of Zc
  double systemic_arterial_pressure_mmhg = 0;  // across the compliance C (downstream of Zc)
  double pulmonary_venous_pressure_mmhg = 0;
  double mitral_flow_ml_s = 0;            // + : LA -> LV
  double aortic_flow_ml_s = 0;            // + : LV -> aorta
  double systemic_flow_ml_s = 0;          // through R_s, into C_pv
  double pulmonary_venous_flow_ml_s = 0;  // through R_pv, into the LA
  // V_lv + V_la + stressed volumes of C and C_pv: constant in time for elastance chambers
  // (the flows only move blood around the loop); external chambers add what they impose.
  double total_volume_ml = 0;
  // External and pressure-driven chambers only (0 otherwise): d(net outflow)/d(chamber
  // pressure) at this instant,
  // the sum of the slopes of the chamber's in- and outflow laws. A strongly coupled caller
  // estimates d(pressure)/d(volume imposed at the end of a step dt) as 1 / (dt * this).
  double lv_outflow_conductance_ml_s_per_mmhg = 0;
  double la_outflow_conductance_ml_s_per_mmhg = 0;
};

class Circulation {
 public:
  // Valid from construction, at t = 0 = LV activation onset. The initial state distributes
  // lumped.stressed_blood_volume_ml (README "Initial state"). Throws InputError when an
  // external chamber is combined with an adjacent valve inertance or with a zero valve leak
  // (both make its pressure undefined), std::invalid_argument for a negative external volume.
  explicit Circulation(const config::Scenario& scenario, const ExternalVolumes& external = {},
                       const PressureDriven& pressure_driven = {});

  // Pressure-driven chambers: their pressures from now on (held over each step).
  void set_imposed_pressures(const ImposedPressures& p) { imposed_ = p; }
  const ImposedPressures& imposed_pressures() const { return imposed_; }

  // Advances the state from time_s() to time_s() + dt_s with one classical RK4 step.
  // External chambers: external_at_end gives their volumes at the end of the step; within
  // the step they change linearly, and their pressure at each stage is the one for which the
  // valve flows match that volume rate. Inertial valve flows are clamped after the step so a
  // closed valve passes no more than its leak. Throws InstabilityError on a non-finite state or
  // a negative chamber volume, std::invalid_argument on dt_s <= 0 or a missing external volume.
  void advance(double dt_s, const ExternalVolumes& external_at_end = {});

  double time_s() const { return time_s_; }
  // Pressures, volumes and flows at time_s() (for external chambers, with the volume rate of
  // the latest step).
  Readout readout() const;

  bool lv_external() const { return lv_external_; }
  bool lv_pressure_driven() const { return lv_pressure_driven_; }
  bool la_pressure_driven() const { return la_pressure_driven_; }
  bool la_external() const { return la_external_; }
  double period_s() const { return lv_elastance_.timing.period_s; }
  // Where the activations change formula within one period, sorted, in [0, period); a fixed
  // step that lands on them keeps RK4 at fourth order (see simulate.cc).
  std::vector<double> activation_breakpoints_s() const;

 private:
  enum Index { kLv = 0, kLa, kSystemic, kPulmonary, kMitralFlow, kAorticFlow, kSize };
  using State = std::array<double, kSize>;
  struct Rates {
    double lv_ml_s = 0, la_ml_s = 0;
  };

  // Right-hand side dy/dt at a state, given the elastances at that time (stage), and for
  // external chambers the imposed volume rates; fills `out` when not null.
  State derivatives(const State& y, double e_lv, double e_la, const Rates& rates,
                    Readout* out) const;
  // Pressures of the external chambers for which the valve flows match the imposed rates.
  void solve_external_pressures(double p_sa, double p_pv, const Rates& rates, double& p_lv,
                                double& p_la) const;
  double mitral_floor(double dp) const;
  void check(const State& y, double t_s, double dt_s) const;

  config::Lumped p_;
  Elastance lv_elastance_, la_elastance_;
  SmoothDiode mitral_, aortic_;  // aortic: the valve in series with Zc (README "Valves")
  bool mitral_inertial_, aortic_inertial_;
  bool lv_external_, la_external_;            // volume imposed
  bool lv_pressure_driven_, la_pressure_driven_;  // pressure imposed
  ImposedPressures imposed_;
  State y_{};
  double time_s_ = 0;
  double lv_elastance_now_ = 0, la_elastance_now_ = 0;  // E(time_s_), reused by the next step
  Rates last_rates_;
  // Warm starts of the external pressure solves (mutable: a cache, not state).
  mutable double lv_pressure_guess_ = 10, la_pressure_guess_ = 10;
};

}  // namespace systole::lumped
