#include "solver/scene/fsei_scene.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "solver/core/errors.h"

namespace systole::scene {

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
  std::vector<std::string> errors;
  config::check_fsei_rules(s, errors);
  if (errors.empty()) return;
  std::string message = errors.size() == 1 ? "invalid scenario: " : "invalid scenario (" + std::to_string(errors.size()) + " problems):\n  ";
  for (std::size_t i = 0; i < errors.size(); ++i) message += (i ? "\n  " : "") + errors[i];
  throw InputError(message);
}

}  // namespace systole::scene
