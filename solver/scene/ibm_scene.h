#pragma once
// Scene "ibm": verification flows of the immersed boundary (solver/ibm) with the fluid
// (solver/fluid), composed here because physics modules never include each other. Everything
// is nondimensional with the body's diameter D (sphere, or tube diameter) and a velocity U:
// Re = U D / ν.
//   fixed_sphere:       a sphere of diameter 1 in a box L_x × L × L (L_x = box_length_diameters,
//                       L = box_diameters), periodic in x and y, free-slip walls at z = 0, L
//                       (ours). A fringe region x ∈ [0, 1.5] relaxes the velocity to the
//                       uniform stream (1, 0, 0) (ours), so the wake leaving at x = L_x comes
//                       back as the free stream; the sphere sits at x = 4 (2.5 D after the
//                       fringe), mid-section in y, z. The fluid starts at u = (1, 0, 0).
//                       Blockage: the cross-section L² holds one sphere (area ratio
//                       π/(4L²)), laterally periodic images (docs/ibm.md). C_D = F_x/(½U²π/4).
//   oscillating_sphere: the sphere moves x_c(t) = x₀ + A(1 − cos ωt) in fluid at rest
//                       (ω = 2π·frequency); the uniform force g = −F_IB/V_box keeps the box-mean
//                       velocity 0 (a closed container, ours). Hydrodynamic force on the body
//                       (Uhlmann 2005 J. Comput. Phys. 209:448, eq for rigid particles):
//                       F_h = −Σ F_b ΔV_b + V_s a. Its in-phase part with the acceleration,
//                       C_a = −⟨F_h a⟩/(V_s⟨a²⟩) over whole periods after the first, against the
//                       unsteady Stokes solution C_a = ½ + 9δ/(4R), δ = √(2ν/ω) (Stokes 1851;
//                       Landau & Lifshitz, Fluid Mechanics, 2nd ed. 1987, §24 problem 5).
//   womersley_pipe:     a tube of diameter 1 along x made of IB markers in a box
//                       L_x × 1.5 × 1.5 (L_x = 0.5), driven by f_x = cos ωt, ω from the
//                       Womersley number Wo = R√(ω Re); starts on the analytic periodic
//                       solution inside the tube (Womersley 1955 J. Physiol. 127:553) and runs
//                       whole periods; error = max |u − u_exact| over faces inside the tube over
//                       the samples, relative to the analytic peak.
//   orifice_plate:      the rigid valvular plane with one opening (MODEL.md §4): a plate across
//                       a duct L × L × L (periodic in x and y, no-slip walls at z = 0, L), in the
//                       plane x = L/2, with a circular hole of diameter 1 at its centre, driven
//                       by a uniform f_x = G, G = 6π/(L Re) (ours: the pressure jump G L would
//                       give a mean hole velocity 1 in Sampson's Stokes flow through a hole,
//                       Q = Δp a³/(3μ); Sampson 1891 Phil. Trans. R. Soc. A 182:449). The plate
//                       is MLS markers (spanning z ∈ [h, L − h]; the hole's rim retracted into
//                       the plate by r_d h when retraction_cells > 0) or the seed's eq 4
//                       (first_node_plane, solver/ibm/plane_forcing.h, spanning the whole
//                       section). At the first sample at or after end_time/2 the hole's cover
//                       (its own marker set, or its own eq 4 plane) is switched on: the flow rate
//                       through the duct must drop to the leak.
#include <mpi.h>

#include <filesystem>
#include <functional>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/run_result.h"
#include "solver/scene/run_control.h"

namespace systole::scene {

enum class IbmCase { fixed_sphere, oscillating_sphere, womersley_pipe, orifice_plate };
const char* to_string(IbmCase c);
// Throws InputError "ibm.verification_case = 'x' is unknown; known: ...".
IbmCase parse_ibm_case(const std::string& name);

struct IbmCaseSpec {
  IbmCase case_name = IbmCase::fixed_sphere;
  double reynolds = 20;          // U D / ν
  double diameter_cells = 10;    // D / h (the grid is cubic, h = 1/diameter_cells)
  double box_diameters = 4;      // sphere cases: the box side L in diameters (fixed_sphere: y, z)
  double box_length_diameters = 12;  // fixed_sphere: the streamwise length L_x, [6, 64]
  double end_time = 5;           // in D/U (womersley_pipe: rounded up to whole periods)
  double cfl = 0.2;
  double max_dt = 0.02;
  int forcing_iterations = 1;    // multi-direct forcing passes (1 = the seed)
  double retraction_cells = 0;   // r_d: markers retracted into the body by r_d h (Breugem 2012)
  bool first_node_plane = false; // orifice_plate: the plate by eq 4 instead of MLS markers
  bool carry_over_force = false; // ForcingParameters::carry_over (forcing.h)
  double frequency = 1;          // oscillating_sphere: cycles per time unit
  double amplitude = 0.01;       // oscillating_sphere: A in diameters
  double womersley_number = 4;   // womersley_pipe
  int samples = 50;              // time-series points (progress reports, cancel polls)
  std::filesystem::path output_dir;  // non-empty: ibm_fields.h5/.xmf and ibm_markers.csv there
};

// Runs the case on comm (every rank gets the same result). metrics (all cases): steps,
// end_time, cells, ranks, markers, tiling_level, slip_rms_final, slip_max_final (after the
// projection, at the markers), slip_rms_mean (of the samples in the second half of the run),
// forcing_slip_rms_final (û at the markers before forcing),
// max_divergence_final, wall_time_ibm_s, wall_time_fluid_s, cancelled, fields_written.
// fixed_sphere: drag_coefficient (mean over the last 20 % of the samples), drag_coefficient_final,
//   drag_coefficient_loads (the surface loads of eq 11, 14 at the last samples), lift_coefficient_final,
//   blockage_area_ratio.
// oscillating_sphere: added_mass_coefficient, added_mass_coefficient_stokes (the reference),
//   added_mass_relative_error, stokes_layer_thickness.
// womersley_pipe: error_linf_relative, reference_peak_velocity, periods.
// orifice_plate: flow_rate_open (Q through the duct when the cover switches on), flow_rate_closed
//   (at the end), closed_to_open_flow_ratio, hole_mean_velocity_open (Q/(π/4)),
//   plate_force_x_open (on the plate), cover_switch_time, driving_force_density; series flow_rate.
// series: time_s (time units × time_scale_s), force_x, force_y, force_z (on the body; each the
// impulse mean ∫F dt/∫dt over the interval since the previous sample, also for the drag), slip_rms.
RunResult run_ibm_case(const IbmCaseSpec& spec, MPI_Comm comm, double time_scale_s = 1.0,
                       const std::function<void(const ProgressReport&)>& progress = {},
                       const std::function<bool()>& cancel = {});

// Scene "ibm": the scenario's ibm section → IbmCaseSpec, run on MPI_COMM_WORLD (the caller has
// initialised MPI). Times are reported with the time unit D/U = 1 s (nondimensional scene).
// Fields and markers go to control.output_directory() when ibm.write_fields is set.
RunResult run_ibm(const config::Scenario& scenario, RunControl& control);

// The metrics every ibm case reports (tests/unit/scene_test.cc checks them).
const std::vector<std::string>& ibm_metric_names();

}  // namespace systole::scene
