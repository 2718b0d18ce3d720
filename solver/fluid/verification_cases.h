#pragma once
// Verification flows with exact solutions, ready for scene/ to run as the `fluid` scene (and for
// tests and bench). Each case fixes its box and walls; the spec gives resolution and physics.
//   taylor_green_2d: box 2π×2π×(nz·2π/nx), free-slip walls; u = sin x cos y e^{−2t/Re},
//                    v = −cos x sin y e^{−2t/Re} (exact decay).
//   poiseuille:      box 1×1×1 (nx, ny may be small), no-slip walls, body force G = 8/Re
//                    from rest; steady u = 4 z (1 − z) (peak 1). Carreau–Yasuda: the same G;
//                    the steady profile of the stress balance τ(z) = G (1/2 − z), computed by
//                    plane_poiseuille_velocity (viscosity.h) at the grid's z levels.
//   couette:         as poiseuille, no force, top wall moving at u = 1; steady u = z (also
//                    for Carreau–Yasuda: the shear rate, hence ν, is uniform).
//   womersley:       box 1×1×2, no-slip walls, f_x = cos(ω t), ω from the Womersley number
//                    Wo = (Lz/2) √(ω Re); starts on the analytic periodic solution.
//   taylor_green_3d: box 2π×2π×π, free-slip walls (the symmetry planes of the periodic flow);
//                    u = sin x cos y cos z, v = −cos x sin y cos z, w = 0 at t = 0; decays
//                    nonlinearly (energy balance dE/dt = −ε checked).
#include <mpi.h>

#include <filesystem>
#include <functional>
#include <string>

#include "solver/core/run_result.h"
#include "solver/fluid/viscosity.h"

namespace systole::fluid {

enum class VerificationCase { taylor_green_2d, poiseuille, couette, womersley, taylor_green_3d };
const char* to_string(VerificationCase c);
// Throws InputError "fluid.verification_case = 'x' is unknown; known: taylor_green_2d, ...".
VerificationCase parse_verification_case(const std::string& name);

struct FluidCaseSpec {
  VerificationCase case_name = VerificationCase::taylor_green_2d;
  int nx = 32, ny = 32, nz = 4;   // cells (AFiD's "points" minus one)
  double reynolds = 100;          // Re, nondimensional
  double end_time = 1.0;          // nondimensional (units of d_m/U_m)
  double cfl = 0.2;               // target CFL
  double max_dt = 0.01;           // nondimensional cap
  bool adaptive_dt = true;        // false: every step is max_dt (time-convergence studies)
  double womersley_number = 4;    // womersley only
  int samples = 50;               // points of the time series (and of the progress reports)
  std::filesystem::path output_dir;  // non-empty: write fluid_fields.h5/.xmf there at the end
  bool write_velocity = true, write_pressure = true, write_vorticity = true;  // which fields
  double time_scale_s = 0.04;     // d_m/U_m: converts to the time_s series
  // "newtonian" (ν = 1/reynolds) or "carreau_yasuda" (law below; only poiseuille and couette,
  // the cases with a reference solution for it: InputError otherwise).
  std::string viscosity_model = "newtonian";
  CarreauYasuda carreau_yasuda = blood_carreau_yasuda();
  // FluidParameters::subgrid_model and its constant (ours); every case takes it, its error then
  // includes the model's O(Δ²) departure from the exact (DNS) solution.
  std::string subgrid_model = "none";
  double subgrid_constant = 0.07;
};

// Runs the case on `comm` (1 rank works without mpirun; every rank calls it and gets the same
// result). progress (optional) is called at every sample; cancel (optional) is polled at every
// sample, its answers OR-ed over ranks; a cancelled run returns what it has with
// metrics["cancelled"] = 1. Throws InputError (bad spec) or InstabilityError (blow-up).
// metrics: error_l2_relative, error_linf_relative (final time, relative to the exact peak
//   velocity; not for taylor_green_3d), womersley: error_linf_max_over_samples_relative;
//   max_divergence_all_steps, mass_flux_relative_variation (max − min over the x-planes of the
//   volume flux, over Ly·Lz·peak), kinetic_energy_final,
//   energy_balance_relative_error (taylor_green_3d), steps, end_time, last_dt,
//   poisson_self_test_relative_divergence, cells, ranks, cancelled, fields_written (1 when
//   output_dir was set), max_viscosity (the largest ν of the last step; 1/Re when Newtonian),
//   reference_peak_velocity (poiseuille, couette: the exact/reference peak the errors are
//   relative to).
// series: time_s, kinetic_energy, dissipation, max_divergence.
RunResult run_verification_case(const FluidCaseSpec& spec, MPI_Comm comm,
                                const std::function<void(const ProgressReport&)>& progress = {},
                                const std::function<bool()>& cancel = {});

}  // namespace systole::fluid
