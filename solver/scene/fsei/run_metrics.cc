#include "solver/scene/fsei/run_metrics.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/diagnostics/phase_average.h"
#include "solver/scene/fsei/fields.h"
#include "solver/scene/h5_dataset.h"
#include "solver/scene/fsei_scene.h"

namespace systole::scene::fsei {
namespace {

double max_of(const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); }
double min_of(const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); }
double largest(const std::vector<double>& v) {  // the sample of largest magnitude, signed
  double best = 0;
  for (double x : v)
    if (std::abs(x) > std::abs(best)) best = x;
  return best;
}

// The run's extremes of the series and the LV's volume balance.
void series_metrics(const SeriesRecorder& series, std::map<std::string, double>& M) {
  const std::vector<double>& t_ms = series.times_ms();
  auto v = [&](const char* name) -> const std::vector<double>& { return series.values(name); };
  M["lv_pressure_start_mmhg"] = v("lv_pressure_mmhg").front();
  M["lv_pressure_max_mmhg"] = max_of(v("lv_pressure_mmhg"));
  M["la_pressure_max_mmhg"] = max_of(v("la_pressure_mmhg"));
  M["aortic_root_pressure_max_mmhg"] = max_of(v("aortic_root_pressure_mmhg"));
  M["lv_volume_start_ml"] = v("lv_volume_ml").front();
  M["lv_volume_min_ml"] = min_of(v("lv_volume_ml"));
  M["lv_volume_end_ml"] = v("lv_volume_ml").back();
  M["la_volume_start_ml"] = v("la_volume_ml").front();
  M["la_volume_end_ml"] = v("la_volume_ml").back();
  M["aortic_flow_max_ml_s"] = max_of(v("aortic_flow_ml_s"));
  M["aortic_flow_min_ml_s"] = min_of(v("aortic_flow_ml_s"));
  M["mitral_flow_max_ml_s"] = max_of(v("mitral_flow_ml_s"));
  M["mitral_flow_min_ml_s"] = min_of(v("mitral_flow_ml_s"));
  // the volume a flow series (ml/s) carried over the run: the trapezoidal ∫ over the samples
  auto volume_ml = [&](const std::vector<double>& q_ml_s) {
    double ml = 0;
    for (std::size_t i = 1; i < t_ms.size(); ++i) ml += 0.5 * 1e-3 * (t_ms[i] - t_ms[i - 1]) * (q_ml_s[i] + q_ml_s[i - 1]);
    return ml;
  };
  // what the LV lost beyond what left through its orifices: the leak of the immersed boundary
  // across the wall and the closed leaflets (ours); the same leak seen at the LV's markers and at
  // the plane's (out of the LV positive): together −lv_volume_balance_ml when the slip at the
  // markers is the whole leak
  M["lv_volume_balance_ml"] =
      (v("lv_volume_ml").back() - v("lv_volume_ml").front()) + volume_ml(v("aortic_flow_ml_s")) - volume_ml(v("mitral_flow_ml_s"));
  if (series.has(SeriesGroup::kWallSlip)) {
    M["lv_wall_slip_volume_ml"] = volume_ml(v("lv_wall_slip_flux_ml_s"));
    M["valvular_plane_slip_volume_ml"] = volume_ml(v("valvular_plane_slip_flux_ml_s"));
  }
  M["kinetic_energy_max_mj"] = max_of(v("kinetic_energy_mj"));
  if (series.has(SeriesGroup::kHeartKineticEnergy)) M["heart_kinetic_energy_max_mj"] = max_of(v("heart_kinetic_energy_mj"));
  M["lv_twist_peak_deg"] = largest(v("lv_twist_deg"));
  M["lv_longitudinal_strain_min"] = min_of(v("lv_longitudinal_strain"));
  M["lv_circumferential_strain_min"] = min_of(v("lv_circumferential_strain"));
  M["mitral_tip_velocity_max_m_s"] = max_of(v("mitral_tip_velocity_m_s"));
  M["aortic_tip_velocity_max_m_s"] = max_of(v("aortic_tip_velocity_m_s"));
  M["aortic_cusps_wss_max_pa"] = max_of(v("aortic_cusps_wss_max_pa"));
}

// The run's cost and size: the modules' steps and wall times, the coupling's passes.
void cost_metrics(const CoupledHeart& h, const CoupledStep& step, int field_frames, std::map<std::string, double>& M) {
  const auto& st = step.stats();
  M["fluid_steps"] = static_cast<double>(st.modules[step.fluid_stage()].steps);
  M["structure_substeps"] = static_cast<double>(st.modules[step.structure_stage()].steps);
  // the tissue's own steps from its t = 0 (the LA stimulus: the av delay's pre-run included, and
  // those before a checkpoint); the scheduler's calls of the EP stage are more (sub-cycles of
  // each pass, replays after a restore)
  M["ep_steps"] = static_cast<double>(h.tension.ep_steps());
  M["coupling_intervals"] = static_cast<double>(st.intervals);
  // strong coupling: passes in all (= intervals when loose), intervals that ended at the pass
  // limit, and the largest relative change of the transferred data at an interval's end
  M["coupling_passes"] = static_cast<double>(st.passes);
  M["coupling_unconverged_intervals"] = static_cast<double>(st.unconverged_intervals);
  M["coupling_max_final_residual"] = st.max_final_residual;
  double over = 0;
  for (const auto& m : st.modules) over = std::max(over, m.max_step_over_limit);
  M["max_step_over_limit"] = over;
  M["grid_cells"] = static_cast<double>(h.grid.cells());
  M["markers"] = static_cast<double>(h.markers.size());
  M["shell_nodes"] = static_cast<double>(shell_node_total(h.group));
  M["field_frames"] = field_frames;
  M["ep_wall_s"] = h.tension.with_ep() ? st.modules[step.ep_stage()].wall_time_s : 0.0;
  M["fluid_wall_s"] = st.modules[step.fluid_stage()].wall_time_s;
  M["structure_wall_s"] = st.modules[step.structure_stage()].wall_time_s;
}

// Per-beat metrics, the last whole beat's also at the top (metrics.json, systole-plot-beat;
// present only when a beat completed), and the phase averages over the whole beats after the
// first (the seed's statistics) in bins of 0.01 T (ours), or of two sample intervals when the
// sampling is coarser (so that every bin holds a sample).
void beat_results(const config::Scenario& s, RunResult& result) {
  auto& M = result.metrics;
  const double period_ms = s.period_ms();
  std::vector<std::map<std::string, double>> beats =
      fsei_beat_metrics(result.series, period_ms, s.fluid.density_kg_per_m3, s.scene);
  M["beats_completed"] = static_cast<double>(beats.size());
  M["heart_rate_bpm"] = 60000.0 / period_ms;
  if (!beats.empty())
    for (const auto& [key, value] : beats.back())
      if (!M.count(key)) M[key] = value;
  if (s.outputs.metrics) result.beats = std::move(beats);
  const int bins = std::min(100, static_cast<int>(std::floor(period_ms / (2 * s.outputs.time_series_interval_ms))));
  if (M["beats_completed"] >= 2 && bins >= 1) {
    try {
      result.phase_averaged = diagnostics::phase_averaged_series(result.series, 1e-3 * period_ms, bins, 1);
    } catch (const std::invalid_argument& e) {  // the run's results stand without them
      result.notes.push_back(std::string("phase averages not computed: ") + e.what());
    }
  }
}

std::string slabs_note(const CoupledHeart& h) {
  std::ostringstream m;
  m << "the fluid's " << h.grid.nz() << " z planes over " << h.slabs.size() << " ranks (fsei.slab_split = "
    << h.s.fsei.slab_split << "):";
  for (int r = 0; r < h.slabs.size(); ++r) {
    const grid::Range z = h.slabs.z_range(r);
    long in = 0;
    for (double mz : h.marker_z_at_rest) {
      const int k = std::clamp(static_cast<int>(std::floor(mz / h.grid.dz())), 0, h.grid.nz() - 1);
      in += k >= z.begin && k < z.begin + z.count;
    }
    m << (r ? "," : "") << " rank " << r << " planes [" << z.begin << ", " << z.begin + z.count << ") with " << in
      << " of the " << h.marker_z_at_rest.size() << " markers at rest";
  }
  return m.str();
}

std::string aorta_note(const CoupledHeart& h) {
  const config::Fsei& fs = h.s.fsei;
  std::ostringstream m;
  m << "aorta pre-tension: ground pressure " << fs.aorta.ground_pressure_mmhg << " mmHg (";
  const double wall_share = h.aorta.wall_share();
  if (const auto& p = h.aorta.prestress())
    m << (wall_share < 1 ? std::to_string(wall_share) + " of it by " : std::string())
      << "a pre-stress of the wall: springs shortened by " << 100 * p->mean_strain << " % on average, "
      << 100 * p->max_strain << " % at most (spring " << p->max_strain_spring << "), " << p->compressed_springs
      << " pre-compressed (down to " << 100 * p->min_strain << " %), equilibrium residual " << p->residual_relative
      << " of the load; "
      << (wall_share < 1 ? "the rest by an outer load on the wall outside the Darcy region; " : "");
  else
    m << "outer load on the wall outside the Darcy region; ";
  if (fs.aorta.pressure_ramp_ms > 0)
    m << "ramped over " << fs.aorta.pressure_ramp_ms << " ms from the blood at rest)";
  else
    m << "the blood inside the aorta, " << h.aorta_initial_ml << " ml, started at it)";
  return m.str();
}

// How the run was set up, for the result's notes.
void setup_notes(const CoupledHeart& h, RunResult& result) {
  const config::Fsei& fs = h.s.fsei;
  const GridPoints& pts = h.points;
  result.notes.push_back("scene " + h.s.scene + " at resolution " + fs.resolution + " (" + std::to_string(pts.nx) + "x" +
                         std::to_string(pts.ny) + "x" + std::to_string(pts.nz) + " points), " +
                         std::to_string(h.markers.size()) + " markers; chamber pressures relative to the outer-fluid probe");
  std::ostringstream m;
  m << "markers per body (tiling level m, markers):";
  for (const auto& b : h.markers.bodies()) m << " " << b.name << " m=" << b.tiling_level << " " << b.marker_count << ";";
  result.notes.push_back(m.str());
  const ibm::DirectForcing::ExclusionRadii rings = h.forcing.carry_over_exclusion_radii();
  if (h.forcing_parameters.carry_over && rings.rigid_wall_cells > 0) {
    std::ostringstream c;
    c << "carry-over forcing: " << h.forcing.carry_over_excluded() << " of " << h.markers.size()
      << " markers (those within " << rings.pair_cells << " h of another body's, " << rings.rigid_cells
      << " h of the plane's (walls: " << rings.rigid_wall_cells << " h), at the end) carry nothing over";
    result.notes.push_back(c.str());
  }
  if (fs.aorta.ground_pressure_mmhg > 0) result.notes.push_back(aorta_note(h));
}

}  // namespace

RunResult finish_result(const CoupledHeart& h, const CoupledStep& step, SeriesRecorder& series,
                        const FieldFrames& frames, const ValveSwitches& valves, const RunFacts& facts,
                        const Resume& resume, const std::filesystem::path& output_directory,
                        const std::filesystem::path& checkpoint_root) {
  RunResult result;
  auto& M = result.metrics;
  series_metrics(series, M);
  M["simulated_time_ms"] = facts.end_time_ms;
  M["resumed_from_ms"] = facts.resumed_from_ms;
  cost_metrics(h, step, frames.frames(), M);
  result.series = series.named();
  beat_results(h.s, result);
  for (std::string& note : series.absent_notes()) result.notes.push_back(std::move(note));
  if (h.slabs.size() > 1) result.notes.push_back(slabs_note(h));
  if (std::string note = valves.limiter_note(); !note.empty()) result.notes.push_back(note);
  setup_notes(h, result);
  diagnostics::FieldPhaseAverage& wss_phase = series.wss_phase();
  if (wss_phase.beats(0) > 0 && !output_directory.empty()) {
    if (is_rank_zero()) {
      std::vector<std::string> names(deformable_bodies().begin(), deformable_bodies().end());
      write_wss_phase_average(output_directory, h.group, names, wss_phase);
    }
    const double from_ms = series.wss_phase_from_ms();
    result.notes.push_back("wall shear stress per shell node phase-averaged over " + std::to_string(wss_phase.beats(0)) +
                           " beats after the first (mean and rms, " + std::to_string(SeriesRecorder::kWssPhaseBins) +
                           " phase bins" +
                           (from_ms > 0 ? ", sampled from the resume at " + std::to_string(from_ms) + " ms" : std::string()) +
                           "): fsei_wss_phase.xmf");
  }
  for (std::string& note : frames.notes(resume.directory.has_value())) result.notes.push_back(std::move(note));
  if (resume.directory) {
    std::ostringstream m;
    m << "resumed from the checkpoint at t = " << resume.time_ms() << " ms in " << resume.directory->string();
    result.notes.push_back(m.str());
  }
  if (facts.checkpoints_written > 0)
    result.notes.push_back(std::to_string(facts.checkpoints_written) + " checkpoints written every " +
                           std::to_string(h.s.fsei.checkpoint_interval_ms) + " ms into " + checkpoint_root.string());
  if (!is_rank_zero()) result.notes.clear();
  return result;
}

}  // namespace systole::scene::fsei
