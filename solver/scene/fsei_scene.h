#pragma once
// Scenes "fsei" and "fsi" (issue #9, docs/fsei.md): the procedural left heart immersed in the
// blood of the fluid box, every body forced by direct forcing (the seed's MLS, or the divergence-
// free kernel of the calibrated defaults: fsei.forcing.kernel), the deformable ones moved by
// their thin shells, the LV and LA contracting (fsei: tension from the EP of the electro scene;
// fsi: a prescribed activation waveform instead of EP). One synchronisation interval of the
// multirate scheduler reads like the seed's Fig. 6:
//   1. tension: EP steps at its own step to t + Δt_sync (fsei) or the waveform is evaluated
//      (fsi); the tension moves to the LV and LA shells;
//   2. fluid: the fluid sub-cycles at its own stable step (CFL, viscous bound) with every body's
//      markers at the held node positions and velocities (eq 1–10); the loads of eq 11–14 at
//      the end go to the shells' nodes (the tiling maps' transposes);
//   3. structure: all deformable bodies sub-cycle together at their stable step with contact
//      between them (structure::BodyGroup), loads and tension held; their nodes go back to the
//      markers.
// Boundary conditions (MODEL.md §2): the valvular plane is rigid (MLS, ours: the seed uses
// eq 4); the pulmonary-vein ostia are open to the outer fluid and closed by marker caps from the
// LA stimulus to the LV stimulus (atrial contraction); the blood leaves the aorta through a
// Darcy region at the end of the descending aorta (fluid.darcy_permeability). The run starts at
// the LV stimulus (beginning of systole) with the valves closed and the fluid at rest; EP is
// pre-run alone from the LA stimulus (ours). The aorta is "pretensioned" to the ground pressure
// fsei.aorta.ground_pressure_mmhg: the blood in its lumen starts at that pressure and an outer
// pressure as large acts on its wall outside the Darcy region (ours: it stays on; with
// fsei.aorta.pressure_ramp_ms > 0 the outer load is ramped from blood at rest instead).
// Chamber pressures are spatial means over probe spheres inside the LV, LA and aortic root,
// relative to a probe in the outer fluid (ours: the box's pressure level is arbitrary).
// Checkpoints (fsei/checkpoint.h): with a RunControl::checkpoint_directory(), the whole coupled
// state is written there every fsei.checkpoint_interval_ms and on cancel, and a run that finds
// a checkpoint of the same scenario there resumes from it, bitwise as the straight run;
// metric resumed_from_ms says where the run started (0: from t = 0).
#include <map>
#include <string>
#include <vector>

#include "solver/config/fsei_rules.h"
#include "solver/config/scenario.h"
#include "solver/grid/grid.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

// The grid points of a resolution preset (config::fsei_grid_points, solver/config/fsei_rules.h).
using config::GridPoints;
using config::fsei_grid_points;

// The scene's input rules, config::check_fsei_rules (parse_scenario checks them at submit): an
// InputError naming every offending field, its value and what is allowed. run_fsei checks them
// first, for a scenario built without parse_scenario.
void check_fsei_scenario(const config::Scenario& scenario);

// Runs scene "fsei" or "fsi" on MPI_COMM_WORLD (the caller has initialised MPI). Throws
// InputError (geometry outside the box, a grid too coarse for the valves with the minimum,
// bad settings, a checkpoint of another scenario or past the run's end), InstabilityError
// (module, place, time) or Cancelled.
RunResult run_fsei(const config::Scenario& scenario, RunControl& control);

const std::vector<std::string>& fsei_metric_names();

// Per-beat metrics of every whole beat [(b − 1) T, b T] in a run's series (the scene starts at
// the beginning of systole, so a beat runs from systole to the end of diastole): the 0-D
// scene's definitions (solver/diagnostics/beat_metrics.h: EDV, ESV, EF, CO, valve phases, E
// and A waves, ...) with valves open while their flow exceeds 5 % of its peak (ours), and each
// beat's peaks of the kinetic energy, twist, strains, tip velocities, cusps' WSS, LA volume and
// pressure; the aortic closure's twist and the aortic flow's reversal; the open mitral valve's
// mean gradient and effective orifice area (blood of blood_density_kg_per_m3); "beat" (1, 2,
// ...) and "beat_start_s". A beat without samples at both ends (a run that stopped inside it)
// is left out. Needs the series the scene writes and a density > 0 (std::invalid_argument
// otherwise); a non-finite metric is an InstabilityError of `scene`.
std::vector<std::map<std::string, double>> fsei_beat_metrics(const std::vector<Series>& series, double period_ms,
                                                             double blood_density_kg_per_m3, const std::string& scene);

// Whether the mitral limiter holds at time t_ms (structure.mitral_limiter_end_phase): over the
// phases [0, end_phase) of every beat of period_ms, always when end_phase >= 1. The phase is
// read as the scene's intervals are clipped, so a time within 1e-9 ms below a beat's start is
// that beat's start (the limiter holds) and the window's end belongs to the released part.
bool mitral_limiter_holds(double t_ms, double period_ms, double end_phase);

// Scene fsi: the peak of a chamber's prescribed active tension in kPa: the LV's is
// fsei.prescribed_peak_tension_kpa, the LA's that times fsei.prescribed_la_tension_fraction
// (ours). Both chambers follow their 0-D activation shapes (lumped::ChamberTiming) under it.
enum class Chamber { lv, la };
double prescribed_peak_tension_kpa(const config::Fsei& fsei, Chamber chamber);

// The work of each z plane of grid g for fsei.slab_split = "balanced" (grid::Slabs'
// plane_weights; nz entries): its cells (the fluid) plus kIbToFluidWork times the whole grid's
// cells in proportion to the share of the markers in the plane (by their z: the immersed
// boundary works per marker on the rank owning its plane). marker_z in grid units; throws
// std::invalid_argument for none or a non-finite one.
inline constexpr double kIbToFluidWork = 12;  // (ours) measured with perf in the heart: docs/benchmarks.md
std::vector<double> slab_plane_weights(const grid::Grid& g, const std::vector<double>& marker_z);

}  // namespace systole::scene
