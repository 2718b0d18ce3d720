// Scene "electromechanics" (docs/electromechanics.md). One synchronisation interval
// [t, t + Δt_sync] of the multirate scheduler reads like the seed's Fig. 6 without the fluid:
//   1. EP: the bidomain (or monodomain) tissue steps to t + Δt_sync at its own step (eq 21–22);
//      the Nash–Panfilov tension (eq 23) moves to the LV and LA shells (nodes the EP does not
//      cover, the vein caps, get none);
//   2. structure: each chamber wall sub-cycles at its own stable step with the active fibre
//      stress (eq 24) and the uniform cavity pressure held (eq 25);
//   3. circulation: the 0-D loop (valves, aorta, pulmonary veins) advances with the same cavity
//      pressures imposed on its pressure-driven LV (and LA), whose blood volumes move with the
//      valve flows;
//   4. cavity constraint: each chamber's pressure is corrected by a secant step on
//      V_mesh − V_blood (strong coupling: repeated until the pressures stop changing, so the wall
//      holds exactly the blood the valves let in, isovolumic phases included).
// Beats run until the EDV repeats (periodicity_tolerance) or `beats`; the metrics are the last
// beat's. The beat metrics come from solver/diagnostics (the 0-D scene's definitions), twist and
// strains from solver/diagnostics/kinematics relative to the end-diastolic configuration.
#include "solver/scene/electromechanics_scene.h"

#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/coupling/cavity_constraint.h"
#include "solver/coupling/electro_module.h"
#include "solver/coupling/lumped_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/coupling/shell_module.h"
#include "solver/diagnostics/beat_metrics.h"
#include "solver/diagnostics/kinematics.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/chamber_walls.h"
#include "solver/scene/h5_dataset.h"
#include "solver/scene/left_heart_ep.h"
#include "solver/structure/shell.h"

namespace systole::scene {
namespace {

using structure::Vec3;

constexpr double kMlPerMm3 = 1e-3;
double kpa_from_mmhg(double p_mmhg) { return p_mmhg * units::kPaPerMmHg * 1e-3; }

// A chamber whose wall is a 3-D shell.
struct Chamber {
  std::string name;  // "lv", "la"
  std::unique_ptr<structure::ShellModel> model;
  std::unique_ptr<coupling::ShellModule> module;
  std::unique_ptr<coupling::CavityPressureConstraint> constraint;
  std::vector<std::int32_t> ep_node;  // per shell node: its EP node, or -1 (no excitable tissue)
  double volume_ml() const { return model->cavity_volume_mm3() * kMlPerMm3; }
};

// One beat's samples (every time-series interval) and the LV positions at those instants.
struct BeatRecord {
  std::vector<double> time_s, lv_volume_ml, lv_pressure_mmhg, la_volume_ml, la_pressure_mmhg, aortic_pressure_mmhg,
      mitral_flow_ml_s, aortic_flow_ml_s, tension_lv_mean_kpa, mismatch_ml;
  std::vector<std::vector<Vec3>> lv_positions;
  void clear() { *this = BeatRecord{}; }
};

// Node fields of the last beat at field_interval_ms: positions, Vm and tension per chamber.
struct FieldFrame {
  double time_ms = 0;
  std::vector<std::vector<double>> xyz, vm, tension;  // per chamber
};

void write_fields(const std::filesystem::path& dir, const std::vector<Chamber*>& chambers,
                  const std::vector<FieldFrame>& frames) {
  std::filesystem::create_directories(dir);
  const std::filesystem::path h5 = dir / "em_fields.h5";
  const hid_t file = H5Fcreate(h5.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("electromechanics: cannot create " + h5.string());
  auto put = [&](const std::string& name, hid_t type, const void* data, hsize_t rows, hsize_t cols) {
    write_h5_dataset(file, name, type, data, rows, cols, "electromechanics");
  };
  H5Gclose(H5Gcreate2(file, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  H5Gclose(H5Gcreate2(file, "frames", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  for (const Chamber* c : chambers) {
    std::vector<std::int32_t> tri;
    for (const auto& t : c->model->stress_free_mesh().tri) tri.insert(tri.end(), t.begin(), t.end());
    put("mesh/" + c->name + "_triangles", H5T_NATIVE_INT32, tri.data(), tri.size() / 3, 3);
  }
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::string g = "frames/" + std::to_string(k);
    H5Gclose(H5Gcreate2(file, g.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    for (std::size_t c = 0; c < chambers.size(); ++c) {
      const std::string n = g + "/" + chambers[c]->name;
      const auto nodes = chambers[c]->model->node_count();
      put(n + "_positions_mm", H5T_NATIVE_DOUBLE, frames[k].xyz[c].data(), nodes, 3);
      put(n + "_vm_mv", H5T_NATIVE_DOUBLE, frames[k].vm[c].data(), nodes, 1);
      put(n + "_active_tension_kpa", H5T_NATIVE_DOUBLE, frames[k].tension[c].data(), nodes, 1);
    }
  }
  H5Fclose(file);

  std::ofstream x(dir / "em_fields.xmf");
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
    << "  <Grid Name=\"electromechanics\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < frames.size(); ++k) {
    x << "   <Grid Name=\"frame" << k << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
      << "    <Time Value=\"" << frames[k].time_ms << "\"/>\n";
    for (const Chamber* c : chambers) {
      const auto nt = c->model->stress_free_mesh().triangle_count(), nn = c->model->node_count();
      const std::string p = "em_fields.h5:/frames/" + std::to_string(k) + "/" + c->name;
      x << "    <Grid Name=\"" << c->name << "\" GridType=\"Uniform\">\n"
        << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << nt << "\">\n"
        << "      <DataItem Dimensions=\"" << nt << " 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">"
        << "em_fields.h5:/mesh/" << c->name << "_triangles</DataItem>\n     </Topology>\n"
        << "     <Geometry GeometryType=\"XYZ\">\n      <DataItem Dimensions=\"" << nn
        << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << p << "_positions_mm</DataItem>\n"
        << "     </Geometry>\n";
      for (const char* f : {"vm_mv", "active_tension_kpa"})
        x << "     <Attribute Name=\"" << f << "\" AttributeType=\"Scalar\" Center=\"Node\">\n"
          << "      <DataItem Dimensions=\"" << nn << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << p
          << "_" << f << "</DataItem>\n     </Attribute>\n";
      x << "    </Grid>\n";
    }
    x << "   </Grid>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
}

// Index of the sample nearest to time t_s.
std::size_t nearest_sample(const std::vector<double>& time_s, double t_s) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < time_s.size(); ++i)
    if (std::abs(time_s[i] - t_s) < std::abs(time_s[best] - t_s)) best = i;
  return best;
}

// Twist and global strains of the LV over systole, relative to the end-diastolic configuration
// (echocardiography's convention: GLS/GCS are shortening from end-diastole). Twist at end-systole
// (the seed's number) and the peak magnitudes of the strains between end-diastole and
// end-systole.
struct SystolicKinematics {
  double twist_end_systole_deg = 0, twist_peak_deg = 0;
  double longitudinal_strain_peak = 0, circumferential_strain_peak = 0;  // most negative
};
SystolicKinematics systolic_kinematics(const geometry::TriMesh& lv, const BeatRecord& beat, std::size_t ed,
                                       std::size_t es, const Vec3& axis) {
  geometry::TriMesh reference = lv;
  reference.position_mm = beat.lv_positions[ed];
  SystolicKinematics k;
  if (es <= ed) es = beat.lv_positions.size() - 1;  // no closure found: to the end of the beat (ours)
  for (std::size_t i = ed; i <= es; ++i) {
    const diagnostics::WallKinematics w = diagnostics::wall_kinematics(reference, beat.lv_positions[i], axis);
    if (std::abs(w.twist_deg) > std::abs(k.twist_peak_deg)) k.twist_peak_deg = w.twist_deg;
    k.longitudinal_strain_peak = std::min(k.longitudinal_strain_peak, w.longitudinal_strain);
    k.circumferential_strain_peak = std::min(k.circumferential_strain_peak, w.circumferential_strain);
    if (i == es) k.twist_end_systole_deg = w.twist_deg;
  }
  return k;
}


// --- the run's stages ---------------------------------------------------------------------
// Throws InputError listing every problem check_electromechanics finds (for a scenario built
// without parsing; parsed ones were checked at submit).
void throw_if_invalid(const config::Scenario& scenario) {
  std::vector<std::string> problems;
  check_electromechanics(scenario, problems);
  if (!problems.empty()) {
    std::string all;
    for (const auto& p : problems) all += (all.empty() ? "" : "; ") + p;
    throw InputError(all);
  }
}

// A chamber wall (step 3 of the file comment) on `mesh`, its shell module, and the EP node of
// each shell node (source: per EP node its {body, node}), the passive annulus cleared.
std::unique_ptr<Chamber> make_chamber(const std::string& name, const geometry::TriMesh& mesh, int body_index,
                                      const structure::ShellMaterials& materials,
                                      const structure::ShellOptions& shell_options,
                                      const std::vector<std::array<std::int32_t, 2>>& source,
                                      double passive_annulus_mm) {
  auto c = std::make_unique<Chamber>();
  c->name = name;
  c->model = std::make_unique<structure::ShellModel>(mesh, materials, shell_options);
  c->module = std::make_unique<coupling::ShellModule>(*c->model);
  c->ep_node.assign(mesh.node_count(), -1);
  for (std::size_t k = 0; k < source.size(); ++k)
    if (source[k][0] == body_index) c->ep_node[static_cast<std::size_t>(source[k][1])] = static_cast<std::int32_t>(k);
  // The fibrous annulus (ours): the valvular plane's ring is not muscle; contracting triangles
  // pulling on the fixed ring crumpled the edges next to it (docs/electromechanics.md).
  clear_passive_annulus(mesh, passive_annulus_mm, c->ep_node);
  return c;
}

// The chamber's cavity constraint (step 4 of the file comment): its pressure on the wall and on
// the 0-D chamber, whose blood volume (blood_ml) and imposed pressure (p_mmhg) it names by member.
// circulation and imposed must outlive the constraint.
void add_cavity_constraint(Chamber& c, coupling::LumpedModule& circulation, lumped::ImposedPressures& imposed,
                           double lumped::Readout::*blood_ml, double lumped::ImposedPressures::*p_mmhg) {
  constexpr double kInitialSlopeMlPerMmHg = 1.0;  // the secant adapts it from the first interval
  c.constraint = std::make_unique<coupling::CavityPressureConstraint>(
      c.name + "_cavity",
      coupling::CavityPressureConstraint::Access{
          .mesh_volume_ml = [&c] { return c.volume_ml(); },
          .blood_volume_ml = [&circulation, blood_ml] { return circulation.readout().*blood_ml; },
          .time_ms = [&c] { return c.model->time_ms(); },
          .impose_pressure_mmhg =
              [&c, &imposed, &circulation, p_mmhg](double p) {
                c.model->set_cavity_pressure(kpa_from_mmhg(p));
                imposed.*p_mmhg = p;
                circulation.set_imposed_pressures(imposed);
              }},
      0.0, kInitialSlopeMlPerMmHg);
}

// The transfer of step 1: the tissue's Nash–Panfilov tension (eq 23) onto each chamber's shell
// nodes (0 where there is no EP node). shell_tension is its scratch and must outlive it.
coupling::Transfer active_tension_transfer(const electro::TissueSolver& tissue,
                                           std::vector<std::unique_ptr<Chamber>>& chambers,
                                           std::vector<double>& shell_tension) {
  return coupling::Transfer{
      .name = "active_tension",
      .read = [&](std::vector<double>& d) { d = tissue.active_tension_kpa(); },
      .write =
          [&](const std::vector<double>& d) {
            for (auto& c : chambers) {
              shell_tension.assign(c->model->node_count(), 0.0);
              for (std::size_t i = 0; i < shell_tension.size(); ++i)
                if (c->ep_node[i] >= 0) shell_tension[i] = d[static_cast<std::size_t>(c->ep_node[i])];
              c->model->set_active_tension(shell_tension);
            }
          },
      .relaxed = false};
}

// The scheduler's options: the synchronisation step, loose/strong coupling from the scenario,
// no relaxation (the constraint's secant step is the update), the hooks' step limit.
coupling::SchedulerOptions scheduler_options(const config::Scenario& scenario, double sync_ms,
                                             const ElectromechanicsHooks& hooks) {
  coupling::SchedulerOptions options;
  options.sync_step_ms = sync_ms;
  options.mode = scenario.coupling.mode == "strong" ? coupling::CouplingMode::strong : coupling::CouplingMode::loose;
  options.strong_tolerance = scenario.coupling.strong_tolerance;
  options.strong_max_iterations = scenario.coupling.strong_max_iterations;
  options.relaxation = coupling::Relaxation::none;  // the constraint's secant step is the update
  options.step_limit_factor = hooks.step_limit_factor;
  return options;
}

// The coupled state the samplers read (all owned by run_electromechanics).
struct CoupledView {
  const electro::TissueSolver& tissue;
  const coupling::LumpedModule& circulation;
  const std::vector<std::unique_ptr<Chamber>>& chambers;
  const Chamber& lv;
  const Chamber* la;  // null: the LA is the 0-D chamber
  const std::vector<std::array<std::int32_t, 2>>& source;
};

// Appends the state at t_ms to the beat's record: volumes, pressures, flows, the LV's mean
// tension, the wall/blood volume mismatch and the LV node positions.
void sample_beat(BeatRecord& beat, double t_ms, const CoupledView& v) {
  const lumped::Readout r = v.circulation.readout();
  const Chamber& lv = v.lv;
  const Chamber* la = v.la;
  beat.time_s.push_back(t_ms * 1e-3);
  beat.lv_volume_ml.push_back(lv.volume_ml());
  beat.lv_pressure_mmhg.push_back(lv.constraint->pressure_mmhg());
  beat.la_volume_ml.push_back(la ? la->volume_ml() : r.la_volume_ml);
  beat.la_pressure_mmhg.push_back(la ? la->constraint->pressure_mmhg() : r.la_pressure_mmhg);
  beat.aortic_pressure_mmhg.push_back(r.aortic_pressure_mmhg);
  beat.mitral_flow_ml_s.push_back(r.mitral_flow_ml_s);
  beat.aortic_flow_ml_s.push_back(r.aortic_flow_ml_s);
  double sum = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < v.source.size(); ++k)
    if (v.source[k][0] == 0) {
      sum += v.tissue.active_tension_kpa()[k];
      ++n;
    }
  beat.tension_lv_mean_kpa.push_back(n ? sum / static_cast<double>(n) : 0.0);
  double mismatch = std::abs(lv.volume_ml() - r.lv_volume_ml);
  if (la) mismatch = std::max(mismatch, std::abs(la->volume_ml() - r.la_volume_ml));
  beat.mismatch_ml.push_back(mismatch);
  beat.lv_positions.push_back(lv.model->positions_mm());
}

// The node fields at t_ms: per chamber positions, Vm and tension (0 where there is no EP node).
FieldFrame field_frame(double t_ms, const CoupledView& v) {
  FieldFrame f;
  f.time_ms = t_ms;
  for (auto& c : v.chambers) {
    std::vector<double> xyz, vm(c->model->node_count(), 0.0), tau(c->model->node_count(), 0.0);
    for (const auto& p : c->model->positions_mm()) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
    for (std::size_t i = 0; i < vm.size(); ++i)
      if (c->ep_node[i] >= 0) {
        vm[i] = v.tissue.vm_mv()[static_cast<std::size_t>(c->ep_node[i])];
        tau[i] = v.tissue.active_tension_kpa()[static_cast<std::size_t>(c->ep_node[i])];
      }
    f.xyz.push_back(std::move(xyz));
    f.vm.push_back(std::move(vm));
    f.tension.push_back(std::move(tau));
  }
  return f;
}

// Polls cancel (throws Cancelled) and reports progress after interval n of beat b, with the LV state.
void report_em_progress(RunControl& control, const config::Scenario& scenario, double t_ms, int b, long n,
                        long intervals_this_beat, const Chamber& lv, const BeatRecord& beat,
                        const std::map<std::string, double>& last_metrics) {
  if (control.cancel_requested()) throw Cancelled();
  ProgressReport r;
  r.simulated_time_s = t_ms * 1e-3;
  r.beat = b;
  r.beats_total = scenario.beats;
  r.fraction = (static_cast<double>(b - 1) + static_cast<double>(n) / static_cast<double>(intervals_this_beat)) /
               scenario.beats;
  std::ostringstream msg;
  msg << std::setprecision(4) << "LV " << lv.constraint->pressure_mmhg() << " mmHg " << lv.volume_ml()
      << " ml, mean LV tension " << beat.tension_lv_mean_kpa.back() << " kPa, structure step "
      << lv.model->stable_step_ms() << " ms, largest |edge strain| " << lv.model->max_abs_strain();
  r.message = msg.str();
  r.latest_beat_metrics = last_metrics;
  control.on_progress(r);
}

// How a beat is cut into synchronisation intervals and which of them are sampled.
struct EmBeatPlan {
  double period_ms, sync_ms;
  long sample_every, field_every, progress_every;
  bool want_fields;
};

// Advances beat b from beat_start_ms to the synchronisation point nearest b T, so beats do not
// drift from the stimuli (which repeat at exact multiples of the period), sampling the record and
// the field frames; polls cancel and reports progress. Returns the time reached, in ms.
double run_em_beat(coupling::Scheduler& scheduler, const CoupledView& view, const EmBeatPlan& plan, int b,
                   double beat_start_ms, BeatRecord& beat, std::vector<FieldFrame>& frames, RunControl& control,
                   const config::Scenario& scenario, const std::map<std::string, double>& last_metrics) {
  double t_ms = beat_start_ms;
  const double period_ms = plan.period_ms, sync_ms = plan.sync_ms;
  const long intervals_this_beat =
      std::max(1L, std::lround(static_cast<double>(b) * period_ms / sync_ms) - std::lround(beat_start_ms / sync_ms));
  for (long n = 1; n <= intervals_this_beat; ++n) {
    t_ms = beat_start_ms + static_cast<double>(n) * sync_ms;
    scheduler.advance_to(t_ms);
    if (n % plan.sample_every == 0 || n == intervals_this_beat) sample_beat(beat, t_ms, view);
    if (plan.want_fields && n % plan.field_every == 0) frames.push_back(field_frame(t_ms, view));
    if (n % plan.progress_every == 0 || n == intervals_this_beat)
      report_em_progress(control, scenario, t_ms, b, n, intervals_this_beat, view.lv, beat, last_metrics);
  }
  return t_ms;
}

// With fields wanted and frames kept: the last beat's frames in em_fields.h5 (+ .xmf) and a
// note; fields_written is the number of frames written (0: none).
void write_last_beat_fields(RunResult& result, bool want_fields, const std::vector<FieldFrame>& last_frames,
                            const std::vector<std::unique_ptr<Chamber>>& chambers, RunControl& control,
                            double field_interval_ms) {
  result.metrics["fields_written"] = 0;
  if (want_fields && !last_frames.empty()) {
    std::vector<Chamber*> list;
    for (auto& c : chambers) list.push_back(c.get());
    write_fields(control.output_directory(), list, last_frames);
    result.metrics["fields_written"] = static_cast<double>(last_frames.size());
    result.notes.push_back("node positions, Vm and active tension of the last beat every " +
                           std::to_string(field_interval_ms) + " ms in em_fields.h5 (+ em_fields.xmf)");
  }
}

// One beat's metrics and the two numbers the run carries on: its EDV and largest volume mismatch.
struct EmBeatResult {
  std::map<std::string, double> metrics;
  double edv_ml;
  double mismatch_ml;
};

// Beat b's metrics (the 0-D scene's definitions, diagnostics::compute_beat_metrics) with the
// systolic kinematics from end-diastole (mitral closure) to end-systole (aortic closure), LA
// volumes, mismatch and the EDV's change; throws InstabilityError on a non-finite metric.
EmBeatResult em_beat_metrics(const BeatRecord& beat, const geometry::TriMesh& lv_mesh,
                             const geometry::ApexBaseAxis& axis, double beat_start_ms, double period_ms, int b,
                             double previous_edv, double t_ms) {
  diagnostics::BeatSamples s;
  s.time_s = beat.time_s;
  s.lv_volume_ml = beat.lv_volume_ml;
  s.lv_pressure_mmhg = beat.lv_pressure_mmhg;
  s.aortic_pressure_mmhg = beat.aortic_pressure_mmhg;
  s.mitral_flow_ml_s = beat.mitral_flow_ml_s;
  s.aortic_flow_ml_s = beat.aortic_flow_ml_s;
  s.beat_start_s = beat_start_ms * 1e-3;
  s.period_s = period_ms * 1e-3;
  const diagnostics::BeatMetrics bm = diagnostics::compute_beat_metrics(s);
  std::map<std::string, double> m = diagnostics::to_map(bm);
  const double ed_s = bm.mitral_valve.close_phase ? s.beat_start_s + *bm.mitral_valve.close_phase * s.period_s
                                                  : s.beat_start_s;
  const double es_s = bm.aortic_valve.close_phase ? s.beat_start_s + *bm.aortic_valve.close_phase * s.period_s
                                                  : s.beat_start_s + s.period_s;
  const SystolicKinematics k = systolic_kinematics(lv_mesh, beat, nearest_sample(beat.time_s, ed_s),
                                                   nearest_sample(beat.time_s, es_s), axis.direction);
  m["lv_twist_end_systole_deg"] = k.twist_end_systole_deg;
  m["lv_twist_peak_deg"] = k.twist_peak_deg;
  m["global_longitudinal_strain_percent"] = 100 * k.longitudinal_strain_peak;
  m["global_circumferential_strain_percent"] = 100 * k.circumferential_strain_peak;
  m["la_volume_max_ml"] = *std::max_element(beat.la_volume_ml.begin(), beat.la_volume_ml.end());
  m["la_volume_min_ml"] = *std::min_element(beat.la_volume_ml.begin(), beat.la_volume_ml.end());
  m["la_pressure_mean_mmhg"] = diagnostics::time_average(beat.time_s, beat.la_pressure_mmhg);
  const double beat_mismatch = *std::max_element(beat.mismatch_ml.begin(), beat.mismatch_ml.end());
  m["max_volume_mismatch_ml"] = beat_mismatch;
  m["beat"] = b;
  m["beat_start_s"] = s.beat_start_s;
  m["edv_relative_change"] = previous_edv > 0 ? std::abs(bm.edv_ml - previous_edv) / previous_edv : 0.0;
  for (const auto& [key, value] : m)
    if (!std::isfinite(value))
      throw InstabilityError("electromechanics", "beat " + std::to_string(b) + " metric " + key, t_ms * 1e-3,
                             "a non-finite beat metric");
  return {std::move(m), bm.edv_ml, beat_mismatch};
}

// Run facts (electromechanics_metric_names): sizes, steps, the scheduler's statistics and the
// wall time per module (stage 0: EP, 1..chambers: the walls, last: the circulation).
void add_run_metrics(std::map<std::string, double>& M, const coupling::SchedulerStats& st, const CoupledView& v,
                     long long ep_steps) {
  M["lv_nodes"] = static_cast<double>(v.lv.model->node_count());
  M["la_nodes"] = v.la ? static_cast<double>(v.la->model->node_count()) : 0.0;
  M["ep_nodes"] = static_cast<double>(v.tissue.mesh().node_count());
  M["ep_steps"] = static_cast<double>(ep_steps);
  double substeps = 0, structure_wall = 0;
  for (std::size_t i = 1; i <= v.chambers.size(); ++i) {
    substeps += static_cast<double>(st.modules[i].steps);
    structure_wall += st.modules[i].wall_time_s;
  }
  M["structure_substeps"] = substeps;
  M["coupling_intervals"] = static_cast<double>(st.intervals);
  M["coupling_passes_per_interval"] =
      st.intervals ? static_cast<double>(st.passes) / static_cast<double>(st.intervals) : 0.0;
  M["unconverged_intervals"] = static_cast<double>(st.unconverged_intervals);
  double over = 0;
  for (const auto& ms : st.modules) over = std::max(over, ms.max_step_over_limit);
  M["max_step_over_limit"] = over;
  M["ep_wall_s"] = st.modules[0].wall_time_s;
  M["structure_wall_s"] = structure_wall;
  M["lumped_wall_s"] = st.modules.back().wall_time_s;
}

// The last beat's time series (one per BeatRecord column, LV positions excepted).
std::vector<Series> beat_series(const BeatRecord& beat) {
  return {{"time_s", "s", beat.time_s},
          {"lv_pressure_mmhg", "mmHg", beat.lv_pressure_mmhg},
          {"lv_volume_ml", "ml", beat.lv_volume_ml},
          {"la_pressure_mmhg", "mmHg", beat.la_pressure_mmhg},
          {"la_volume_ml", "ml", beat.la_volume_ml},
          {"aortic_pressure_mmhg", "mmHg", beat.aortic_pressure_mmhg},
          {"mitral_flow_ml_s", "ml/s", beat.mitral_flow_ml_s},
          {"aortic_flow_ml_s", "ml/s", beat.aortic_flow_ml_s},
          {"active_tension_lv_mean_kpa", "kPa", beat.tension_lv_mean_kpa},
          {"volume_mismatch_ml", "ml", beat.mismatch_ml}};
}

// The notes a user must see next to the numbers (ours): an unclosed cavity constraint, no
// ejection, and the run's beats and coupling passes.
void add_run_notes(RunResult& result, double max_mismatch_ml, const coupling::SchedulerStats& st, int beats_done,
                   bool periodic) {
  if (max_mismatch_ml > 0.1)
    result.notes.push_back("warning: the cavity constraint left up to " + std::to_string(max_mismatch_ml) +
                           " ml between the wall's and the blood's volume (" +
                           std::to_string(st.unconverged_intervals) +
                           " intervals hit coupling.strong_max_iterations): raise it or shorten "
                           "electromechanics.sync_step_ms");
  if (result.metrics.count("stroke_volume_ml") && result.metrics["stroke_volume_ml"] <= 0)
    result.notes.push_back("warning: no ejection in the last beat (ESV >= EDV): the scene is not calibrated, "
                           "docs/electromechanics.md");
  std::ostringstream note;
  note << beats_done << " beat(s); " << (periodic ? "periodic state reached" : "beats limit reached") << "; "
       << st.intervals << " coupling intervals, " << result.metrics["coupling_passes_per_interval"]
       << " passes per interval";
  result.notes.push_back(note.str());
}

}  // namespace

const std::vector<std::string>& electromechanics_metric_names() {
  static const std::vector<std::string> names{
      "ejection_fraction_percent", "cardiac_output_l_min", "stroke_volume_ml", "edv_ml", "esv_ml",
      "lv_peak_pressure_mmhg", "lv_end_diastolic_pressure_mmhg", "aortic_pressure_max_mmhg",
      "aortic_pressure_min_mmhg", "lv_twist_end_systole_deg", "lv_twist_peak_deg",
      "global_longitudinal_strain_percent", "global_circumferential_strain_percent", "la_volume_max_ml",
      "la_volume_min_ml", "max_volume_mismatch_ml", "beats_simulated", "periodic", "heart_rate_bpm",
      "lv_nodes", "la_nodes", "ep_nodes", "ep_steps", "structure_substeps", "coupling_intervals",
      "coupling_passes_per_interval", "unconverged_intervals", "max_step_over_limit", "ep_wall_s", "structure_wall_s", "lumped_wall_s",
      "fields_written", "wall_time_s"};
  return names;
}

void check_electromechanics(const config::Scenario& scenario, std::vector<std::string>& problems) {
  const double sync_ms = scenario.electromechanics.sync_step_ms;
  const double ep_dt = scenario.electro.time_step_ms;
  const double ratio = sync_ms / ep_dt;
  if (ratio < 1 - 1e-9 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio)
    problems.push_back("electromechanics.sync_step_ms = " + std::to_string(sync_ms) +
                       " ms must be a whole multiple of electro.time_step_ms = " + std::to_string(ep_dt) + " ms");
  if (scenario.electro.mesh != "left_heart")
    problems.push_back("electromechanics needs electro.mesh = \"left_heart\" (got \"" + scenario.electro.mesh + "\")");
}

RunResult run_electromechanics(const config::Scenario& scenario, RunControl& control,
                               const ElectromechanicsHooks& hooks) {
  const config::Electromechanics& em = scenario.electromechanics;
  const double period_ms = scenario.period_ms();
  const double sync_ms = em.sync_step_ms;
  throw_if_invalid(scenario);

  // 1. geometry: the procedural left heart (LV, LA, the valvular plane's anchors)
  const geometry::LeftHeart heart = geometry::build_left_heart(scenario.geometry, scenario.fluid);
  const geometry::TriMesh& lv_mesh = heart.body(geometry::kLvBody);
  const geometry::TriMesh& la_mesh = heart.body(geometry::kLaBody);
  const bool la_shell = em.la_chamber == "shell";

  // 2. EP on the LV and LA walls (left_heart_ep.h: the set-up scene electro uses too)
  LeftHeartEp ep = left_heart_ep(scenario, lv_mesh, la_mesh);
  const std::vector<std::array<std::int32_t, 2>> source = ep.mesh.source_node;
  electro::TissueSolver tissue(std::move(ep.mesh), std::move(ep.options));
  coupling::ElectroModule ep_module(tissue);

  // 3. the chamber walls (passive stiffness scaled, ours: docs/electromechanics.md "Calibration")
  const structure::ShellMaterials materials = chamber_wall_materials(scenario);
  const structure::ShellOptions shell_options = chamber_wall_options(scenario, heart.plane.z_mm);
  std::vector<std::unique_ptr<Chamber>> chambers;
  chambers.push_back(make_chamber("lv", lv_mesh, 0, materials, shell_options, source, em.passive_annulus_mm));
  if (la_shell)
    chambers.push_back(make_chamber("la", la_mesh, 1, materials, shell_options, source, em.passive_annulus_mm));
  Chamber& lv = *chambers[0];
  Chamber* la = la_shell ? chambers[1].get() : nullptr;

  // 4. the 0-D circulation with pressure-driven 3-D chambers, starting from the walls' volumes
  lumped::ExternalVolumes initial;
  initial.lv_ml = lv.volume_ml();
  if (la) initial.la_ml = la->volume_ml();
  coupling::LumpedModule circulation(scenario, initial, lumped::PressureDriven{.lv = true, .la = la != nullptr});

  // 5. the cavity constraints: one pressure per chamber, on the wall and on the 0-D chamber
  lumped::ImposedPressures imposed;
  add_cavity_constraint(lv, circulation, imposed, &lumped::Readout::lv_volume_ml, &lumped::ImposedPressures::lv_mmhg);
  if (la)
    add_cavity_constraint(*la, circulation, imposed, &lumped::Readout::la_volume_ml, &lumped::ImposedPressures::la_mmhg);

  // 6. the stages of one synchronisation interval (Fig. 6 without the fluid)
  std::vector<double> shell_tension;
  const coupling::Transfer tension = active_tension_transfer(tissue, chambers, shell_tension);
  std::vector<coupling::Transfer> constraints{lv.constraint->transfer()};
  if (la) constraints.push_back(la->constraint->transfer());
  std::vector<coupling::Stage> stages{{&ep_module, {tension}}};
  for (auto& c : chambers) stages.push_back({c->module.get(), {}});
  stages.push_back({&circulation, constraints});
  coupling::Scheduler scheduler(stages, scheduler_options(scenario, sync_ms, hooks));

  // 7. beats
  const CoupledView view{tissue, circulation, chambers, lv, la, source};
  const geometry::ApexBaseAxis axis = geometry::apex_base_axis(lv_mesh);
  const long sample_every =
      std::max(1L, std::lround(scenario.outputs.time_series_interval_ms / sync_ms));
  const long field_every =
      em.field_interval_ms > 0 ? std::max(1L, std::lround(em.field_interval_ms / sync_ms)) : 0;
  const bool want_fields = field_every > 0 && !control.output_directory().empty() && is_rank_zero();
  RunResult result;
  BeatRecord beat;
  std::vector<FieldFrame> frames, last_frames;
  double max_mismatch_ml = 0, previous_edv = initial.lv_ml.value_or(0);
  int beats_done = 0;
  bool periodic = false;
  std::map<std::string, double> last_metrics;
  double t_ms = 0;
  // Progress (with the LV state) every ~20 ms of simulated time (ours).
  const long progress_every = std::max(1L, std::lround(20.0 / sync_ms));
  const EmBeatPlan plan{period_ms, sync_ms, sample_every, field_every, progress_every, want_fields};
  for (int b = 1; b <= scenario.beats; ++b) {
    const double beat_start_ms = t_ms;
    beat.clear();
    frames.clear();
    sample_beat(beat, t_ms, view);
    if (want_fields) frames.push_back(field_frame(t_ms, view));
    t_ms = run_em_beat(scheduler, view, plan, b, beat_start_ms, beat, frames, control, scenario, last_metrics);
    // Beat metrics (the 0-D scene's definitions) and systolic kinematics.
    EmBeatResult r = em_beat_metrics(beat, lv_mesh, axis, beat_start_ms, period_ms, b, previous_edv, t_ms);
    std::map<std::string, double>& m = r.metrics;
    max_mismatch_ml = std::max(max_mismatch_ml, r.mismatch_ml);
    if (scenario.outputs.metrics) result.beats.push_back(m);
    last_metrics = m;
    ++beats_done;
    last_frames = frames;
    const bool repeat = b >= 2 && scenario.periodicity_tolerance > 0 && m["edv_relative_change"] < scenario.periodicity_tolerance;
    previous_edv = r.edv_ml;
    if (repeat) {
      periodic = true;
      break;
    }
  }

  // 8. results: the last beat's metrics and series, run facts
  result.metrics = last_metrics;
  for (const char* key : {"beat", "beat_start_s"}) result.metrics.erase(key);
  const coupling::SchedulerStats& st = scheduler.stats();
  result.metrics["max_volume_mismatch_ml"] = max_mismatch_ml;
  result.metrics["beats_simulated"] = beats_done;
  result.metrics["periodic"] = periodic ? 1 : 0;
  result.metrics["heart_rate_bpm"] = scenario.heart_rate_bpm;
  add_run_metrics(result.metrics, st, view, ep_module.tissue_steps());
  if (scenario.outputs.time_series) result.series = beat_series(beat);
  write_last_beat_fields(result, want_fields, last_frames, chambers, control, em.field_interval_ms);
  add_run_notes(result, max_mismatch_ml, st, beats_done, periodic);
  return result;
}

}  // namespace systole::scene
