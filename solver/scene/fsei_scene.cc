#include "solver/scene/fsei_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/core/errors.h"

namespace systole::scene {

GridPoints fsei_grid_points(const config::Scenario& s) {
  const std::string& r = s.fsei.resolution;
  if (r == "custom") return {s.fluid.nx, s.fluid.ny, s.fluid.nz};
  // A preset's points are the for the 140-mm box; a box of another height keeps the
  // preset's spacing in z, rounded to the coarser whole number of cells (ours: at 180 mm, coarse
  // is 65 x 65 x 93 and basic 129 x 129 x 186, docs/fsei.md's runs t120b/la4 and b1).
  auto with_z = [&](int nxy, int nz_at_140) {
    const int cells = static_cast<int>(std::floor((nz_at_140 - 1) * s.fluid.box_z_mm / 140.0 + 1e-9));
    return GridPoints{nxy, nxy, std::max(cells, 2) + 1};
  };
  if (r == "coarse") return with_z(65, 73);
  if (r == "basic") return with_z(129, 145);
  if (r == "fine") return with_z(193, 257);
  if (r == "very_fine") return with_z(257, 290);
  throw InputError("fsei.resolution = \"" + r + "\" is not a preset; allowed: coarse, basic, fine, very_fine, custom");
}

const std::vector<std::string>& fsei_metric_names() {
  static const std::vector<std::string> names{
      "lv_pressure_start_mmhg", "lv_pressure_max_mmhg", "la_pressure_max_mmhg", "aortic_root_pressure_max_mmhg",
      "lv_volume_start_ml", "lv_volume_min_ml", "lv_volume_end_ml", "la_volume_start_ml", "la_volume_end_ml",
      "aortic_flow_max_ml_s", "aortic_flow_min_ml_s", "mitral_flow_max_ml_s", "mitral_flow_min_ml_s",
      "lv_volume_balance_ml", "lv_wall_slip_volume_ml", "valvular_plane_slip_volume_ml", "kinetic_energy_max_mj", "lv_twist_peak_deg", "lv_longitudinal_strain_min",
      "lv_circumferential_strain_min", "mitral_tip_velocity_max_m_s", "aortic_tip_velocity_max_m_s", "aortic_cusps_wss_max_pa", "simulated_time_ms", "fluid_steps", "structure_substeps",
      "ep_steps", "coupling_intervals", "coupling_passes", "coupling_unconverged_intervals",
      "coupling_max_final_residual", "max_step_over_limit", "grid_cells", "markers", "shell_nodes", "field_frames",
      "ep_wall_s",
      "fluid_wall_s", "structure_wall_s", "resumed_from_ms", "beats_completed", "heart_rate_bpm", "wall_time_s"};
  return names;
}

bool mitral_limiter_holds(double t_ms, double period_ms, double end_phase) {
  if (end_phase >= 1) return true;
  const double phase_ms = t_ms - std::floor(t_ms / period_ms + 1e-9) * period_ms;
  return phase_ms < end_phase * period_ms - 1e-9;
}

double prescribed_peak_tension_kpa(const config::Fsei& fsei, Chamber chamber) {
  return chamber == Chamber::lv ? fsei.prescribed_peak_tension_kpa
                                : fsei.prescribed_peak_tension_kpa * fsei.prescribed_la_tension_fraction;
}

namespace {
// The z plane (cell layer) holding a point at z (grid units), clamped into the grid.
int plane_of(const grid::Grid& g, double z) {
  return std::clamp(static_cast<int>(std::floor(z / g.dz())), 0, g.nz() - 1);
}
}  // namespace

std::vector<double> slab_plane_weights(const grid::Grid& g, const std::vector<double>& marker_z) {
  if (marker_z.empty()) throw std::invalid_argument("slab_plane_weights: no markers");
  std::vector<double> markers_in(static_cast<std::size_t>(g.nz()), 0.0);
  for (double z : marker_z) {
    if (!std::isfinite(z)) throw std::invalid_argument("slab_plane_weights: a marker's z is not finite");
    markers_in[static_cast<std::size_t>(plane_of(g, z))] += 1;
  }
  const double plane_cells = static_cast<double>(g.nx()) * g.ny(), n = static_cast<double>(marker_z.size());
  std::vector<double> w(markers_in.size());
  for (std::size_t k = 0; k < w.size(); ++k) w[k] = plane_cells * (1 + kIbToFluidWork * g.nz() * markers_in[k] / n);
  return w;
}

void check_fsei_scenario(const config::Scenario& s) {
  const bool with_ep = s.scene == "fsei";
  const config::Fsei& fs = s.fsei;
  const double sync_ms = fs.sync_step_ms;
  if (fs.aortic_prestress_fraction != 1 && fs.aortic_pretension != "prestress")
    throw InputError("fsei.aortic_prestress_fraction = " + std::to_string(fs.aortic_prestress_fraction) +
                     " is the share of the pre-stress: it needs fsei.aortic_pretension = \"prestress\" (got \"" +
                     fs.aortic_pretension + "\"); with \"outer_load\" leave it at 1");
  if (fs.sync_interval != "fixed" && fs.sync_interval != "fluid_step")
    throw InputError("fsei.sync_interval = \"" + fs.sync_interval + "\" is not one of: fixed, fluid_step");
  if (fs.coupling_order != "fluid_first" && fs.coupling_order != "structure_first")
    throw InputError("fsei.coupling_order = \"" + fs.coupling_order + "\" is not one of: fluid_first, structure_first");
  // Loose coupling in the shells-first order would hand the shells the loads of the last pass
  // without keeping them in a checkpoint; the order is for strong coupling's one-pass intervals.
  if (fs.coupling_order == "structure_first" && !fs.strong_coupling)
    throw InputError("fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true (its point is "
                     "strong coupling's first-pass check); with loose coupling use \"fluid_first\"");
  if (fs.first_pass_predictor != "last" && fs.first_pass_predictor != "linear")
    throw InputError("fsei.first_pass_predictor = \"" + fs.first_pass_predictor + "\" is not one of: last, linear");
  if (fs.first_pass_predictor == "linear" && fs.coupling_order != "structure_first")
    throw InputError("fsei.first_pass_predictor = \"linear\" needs fsei.coupling_order = \"structure_first\" (it "
                     "guesses the loads the shells take before the fluid makes them); got \"" + fs.coupling_order + "\"");
  if (fs.sync_interval == "fixed" && fs.fluid_steps_per_interval != 1)
    throw InputError("fsei.fluid_steps_per_interval = " + std::to_string(fs.fluid_steps_per_interval) +
                     " needs fsei.sync_interval = \"fluid_step\"; with fixed intervals (of fsei.sync_step_ms) leave it at 1");
  if (s.structure.mitral_limiter_end_phase != 1 && !s.structure.mitral_limiter)
    throw InputError("structure.mitral_limiter_end_phase = " + std::to_string(s.structure.mitral_limiter_end_phase) +
                     " is the mitral limiter's window: it needs structure.mitral_limiter = true; without the "
                     "limiter leave it at 1");
  if (with_ep) {
    const double ratio = sync_ms / s.electro.time_step_ms;
    if (ratio < 1 - 1e-9 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio)
      throw InputError("fsei.sync_step_ms = " + std::to_string(sync_ms) +
                       " ms must be a whole multiple of electro.time_step_ms = " +
                       std::to_string(s.electro.time_step_ms) + " ms");
    if (s.electro.mesh != "left_heart")
      throw InputError("scene fsei needs electro.mesh = \"left_heart\" (got \"" + s.electro.mesh + "\")");
  }
  if (fs.slab_split != "balanced" && fs.slab_split != "uniform")
    throw InputError("fsei.slab_split = \"" + fs.slab_split + "\" is not one of: balanced, uniform");
}

}  // namespace systole::scene
