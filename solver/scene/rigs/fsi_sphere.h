#pragma once
// A verification case of the fluid–structure coupling (issue #9, docs/fsei.md): a closed elastic
// membrane (structure::ShellModel, an icosphere centred in the box) pre-stretched and released
// at rest in blood at rest, coupled through the multirate scheduler with coupling::FluidModule
// (MLS direct forcing; loads of eq 11–14 from the inside, as for a chamber) and
// geometry::tiling_map between the shell's nodes and the markers' tiled nodes.
//
// Stages per synchronisation interval: fluid (markers at the held node positions and
// velocities) → loads spread to the shell's nodes (the tiling map's transpose, × ρU²d²) →
// shell (sub-cycled at its stable step) → node positions and velocities → markers.
// The enclosed blood is incompressible, so the membrane should keep its volume; what it loses
// is the immersed boundary's leak. Used by tests/coupling/fsi_sphere_test.cc and
// bench/coupling/fsi_sphere_case.cc. Scales: the seed's d_m = 24 mm, U_m = 0.6 m/s, ρ = 1.05 g/ml.
#include <string>
#include <vector>

#include <mpi.h>

namespace systole::scene {

struct FsiSphereOptions {
  int cells = 32;                   // grid cells per side of the 48 mm periodic box (x, y; z walls)
  double reynolds = 3000;           // the seed's blood
  double radius_mm = 10;            // stress-free radius
  int icosphere_level = 3;          // 642 nodes
  double thickness_mm = 2;
  double stiffness_scale = 20;      // × the seed's LV Fung c (isotropic, α_c = α_f; ours)
  double stretch = 1.1;             // initial radius / stress-free radius
  bool carry_over = true;           // ibm::ForcingParameters::carry_over (false: the seed's forcing)
  double carry_over_factor = 1;     // ibm::ForcingParameters::carry_over_factor
  int forcing_iterations = 1;       // ibm::ForcingParameters::iterations
  bool divergence_free_kernel = false;  // ibm::TransferKernel::divergence_free (false: MLS)
  double marker_retraction_cells = 0;
  double marker_spacing_fraction = 0.7;
  bool strong_coupling = false;     // false: loose (the seed's production runs)
  int strong_passes = 4;
  double sync_step_ms = 0.1;        // also the fluid's largest step (0.5 ms leaked 9 % in 60 ms and
                                    // went unstable at 48^3: docs/fsei.md)
  double end_ms = 60;
  double sample_ms = 5;             // volume samples
};

struct FsiSphereResult {
  double initial_volume_mm3 = 0;
  std::vector<double> time_ms, volume_ratio;  // samples of V / V0
  // The blood's flux through the markers relative to them, −Σ (u(X) − V)·n A (out of the sphere
  // positive), integrated by the trapezoid rule over the samples from t = 0 (where it is 0, at
  // rest), mm³: the leak seen at the markers, to compare with the volume lost (ours; the heart's
  // lv_wall_slip_flux_ml_s). Sample finely (sample_ms) for the integral.
  double slip_volume_mm3 = 0;
  // The same integral of the markers' own velocities, −Σ V·n A (out positive): the volume the
  // fluid was told the wall sweeps, against the shell's true volume change.
  double told_volume_mm3 = 0;
  double min_volume_ratio = 1, max_volume_ratio = 1;
  long long fluid_steps = 0, shell_substeps = 0, passes = 0, unconverged_intervals = 0;
  double max_step_over_limit = 0;       // over both modules
  double mean_wall_pressure = 0;        // area mean of eq 14's wall pressure at the end, ρU²
  std::string stopped;                  // the InstabilityError's message when the run stopped
};

// Throws InputError naming the option for a value out of its range. An instability of a
// module ends the run: the result carries the samples so far and the diagnosis in `stopped`.
FsiSphereResult run_fsi_sphere(const FsiSphereOptions& options, MPI_Comm comm);

// The same membrane without fluid: the lowest V / V0 reached before `end_ms` or before it had
// lost `stop_at_loss` of its volume (it then goes on into compression and crumples), and when.
struct DrySphereResult {
  double min_volume_ratio = 1, time_ms = 0;
};
DrySphereResult run_dry_sphere(const FsiSphereOptions& options, double stop_at_loss);

}  // namespace systole::scene
