// Scene "electro" (docs/electro.md):
//  1. mesh: left heart (LV domain 0 + LA domain 1, geometry::build_left_heart), an imported heart
//     (mesh = "manifest": the lv and/or la bodies of electro.mesh_manifest) or sheet / slab;
//  2. tissue: mono/bidomain (eq 21-22) with the scenario's conductivities, chi, C_m, time step
//     and splitting; cell models per domain (lv_cell_model, la_cell_model);
//  3. stimuli: left heart -> Bachmann bundle (LA, t = 0) and His bundle (LV, t = av_delay_ms),
//     every period (heart rate); sheet/slab -> a cube of edge stimulus.box_size_mm at the
//     origin corner, every period;
//  4. beats: the left heart runs up to `beats` periods, stopping early when the activation
//     pattern repeats (relative change of the total activation time and mean APD90 below
//     periodicity_tolerance, at least 2 beats); a sheet / slab runs end_time_ms as one beat;
//  5. outputs: per-beat metrics, probe potentials (time series), activation-time / APD90 /
//     final potential nodal fields of the last beat in electro_fields.h5 + .xmf.
#include "solver/scene/electro_scene.h"

#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/mesh_io.h"
#include "solver/scene/h5_dataset.h"
#include "solver/scene/left_heart_ep.h"

namespace systole::scene {
namespace {

using electro::ElectroMesh;
using electro::StimulusRegion;
using electro::StimulusSpec;
using electro::Vec3;

using Probe = EpProbe;

std::size_t nearest_node(const ElectroMesh& m, const Vec3& p, int domain = -1) {
  std::size_t best = 0;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    if (domain >= 0 && m.node_domain[i] != domain) continue;
    const double di = (m.position_mm[i] - p).squaredNorm();
    if (di < d) {
      d = di;
      best = i;
    }
  }
  return best;
}

// Activation statistics of one domain (or all nodes if domain < 0), times relative to t0.
struct DomainStats {
  double first_ms = std::numeric_limits<double>::quiet_NaN();
  double last_ms = std::numeric_limits<double>::quiet_NaN();
  double activated_fraction = 0;
  double mean_apd90_ms = std::numeric_limits<double>::quiet_NaN();
};

DomainStats domain_stats(const ElectroMesh& m, const electro::ActivationTracker& tr, int domain, double t0) {
  DomainStats s;
  const auto& act = tr.activation_ms();
  const auto apd = tr.apd_ms();
  std::size_t count = 0, active = 0, with_apd = 0;
  double apd_sum = 0, first = std::numeric_limits<double>::infinity(), last = -first;
  for (std::size_t i = 0; i < m.node_count(); ++i) {
    if (domain >= 0 && m.node_domain[i] != domain) continue;
    ++count;
    if (std::isnan(act[i])) continue;
    ++active;
    first = std::min(first, act[i] - t0);
    last = std::max(last, act[i] - t0);
    if (!std::isnan(apd[i])) {
      apd_sum += apd[i];
      ++with_apd;
    }
  }
  if (active) {
    s.first_ms = first;
    s.last_ms = last;
  }
  s.activated_fraction = count ? static_cast<double>(active) / static_cast<double>(count) : 0.0;
  if (with_apd) s.mean_apd90_ms = apd_sum / static_cast<double>(with_apd);
  return s;
}

// --- nodal fields: HDF5 + XDMF ------------------------------------------------------------
void h5_write(hid_t file, const std::string& name, hid_t type, const void* data, hsize_t rows, hsize_t cols) {
  write_h5_dataset(file, name, type, data, rows, cols, "electro");
}

void write_fields(const std::filesystem::path& dir, const ElectroMesh& m,
                  const std::vector<std::pair<std::string, std::vector<double>>>& fields) {
  std::filesystem::create_directories(dir);
  const auto h5 = dir / "electro_fields.h5";
  const hid_t file = H5Fcreate(h5.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (file < 0) throw std::runtime_error("electro: cannot create " + h5.string());
  std::vector<double> xyz;
  for (const auto& p : m.position_mm) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
  const int k = m.nodes_per_cell();
  std::vector<std::int32_t> cells;
  for (const auto& c : m.cell) cells.insert(cells.end(), c.begin(), c.begin() + k);
  std::vector<std::int32_t> domain(m.node_domain.begin(), m.node_domain.end());
  H5Gclose(H5Gcreate2(file, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  H5Gclose(H5Gcreate2(file, "fields", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  h5_write(file, "mesh/points_mm", H5T_NATIVE_DOUBLE, xyz.data(), m.node_count(), 3);
  h5_write(file, "mesh/cells", H5T_NATIVE_INT32, cells.data(), m.cell_count(), static_cast<hsize_t>(k));
  h5_write(file, "mesh/node_domain", H5T_NATIVE_INT32, domain.data(), m.node_count(), 1);
  for (const auto& [name, values] : fields) h5_write(file, "fields/" + name, H5T_NATIVE_DOUBLE, values.data(), m.node_count(), 1);
  H5Fclose(file);

  std::ofstream x(dir / "electro_fields.xmf");
  const char* topo = m.cell_dim == 2 ? "Triangle" : "Tetrahedron";
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n  <Grid Name=\"electro\" GridType=\"Uniform\">\n"
    << "   <Topology TopologyType=\"" << topo << "\" NumberOfElements=\"" << m.cell_count() << "\">\n"
    << "    <DataItem Dimensions=\"" << m.cell_count() << " " << k
    << "\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">electro_fields.h5:/mesh/cells</DataItem>\n   </Topology>\n"
    << "   <Geometry GeometryType=\"XYZ\">\n    <DataItem Dimensions=\"" << m.node_count()
    << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">electro_fields.h5:/mesh/points_mm</DataItem>\n   </Geometry>\n";
  auto attribute = [&](const std::string& name, const std::string& path, const char* type, int prec) {
    x << "   <Attribute Name=\"" << name << "\" AttributeType=\"Scalar\" Center=\"Node\">\n    <DataItem Dimensions=\""
      << m.node_count() << "\" NumberType=\"" << type << "\" Precision=\"" << prec << "\" Format=\"HDF\">electro_fields.h5:"
      << path << "</DataItem>\n   </Attribute>\n";
  };
  attribute("node_domain", "/mesh/node_domain", "Int", 4);
  for (const auto& f : fields) attribute(f.first, "/fields/" + f.first, "Float", 8);
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
}


// --- the run's stages ---------------------------------------------------------------------
// The scene's inputs to the tissue (step 1 of the file comment): mesh, cell models and stimuli
// (sheet/slab; the heart's come with its options), probes, and the heart's LV/LA domains.
struct ElectroInputs {
  ElectroMesh mesh;
  std::vector<std::string> models;
  std::vector<StimulusSpec> stimuli;
  std::vector<Probe> probes;
  electro::TissueOptions heart_options;
  int lv_domain = -1, la_domain = -1;
};

// Step 1: the left heart (procedural or the manifest's bodies, left_heart_ep.h) or a sheet/slab
// with a corner-box stimulus every period and three probes (origin, centre, far corner).
ElectroInputs electro_inputs(const config::Scenario& scenario, bool heart, double period_ms) {
  const config::Electro& e = scenario.electro;
  ElectroInputs in;
  auto stim = [&](std::string name, StimulusRegion region, double start_ms) {
    in.stimuli.push_back({std::move(name), std::move(region), e.stimulus.amplitude_ua_per_cm2, e.stimulus.duration_ms,
                          start_ms, period_ms});
  };
  if (heart) {
    LeftHeartEp ep;
    if (e.mesh == "manifest") {
      const std::vector<geometry::TriMesh> bodies = load_electro_manifest(e.mesh_manifest);
      const geometry::TriMesh *lv = nullptr, *la = nullptr;
      for (const auto& b : bodies) (b.name == geometry::kLvBody ? lv : la) = &b;
      ep = heart_ep(scenario, lv, la);
    } else {
      const geometry::LeftHeart lh = geometry::build_left_heart(scenario.geometry, scenario.fluid);
      ep = left_heart_ep(scenario, lh.body(geometry::kLvBody), lh.body(geometry::kLaBody));
    }
    in.mesh = std::move(ep.mesh);
    in.heart_options = std::move(ep.options);
    in.probes = std::move(ep.probes);
    in.lv_domain = ep.lv_domain;
    in.la_domain = ep.la_domain;
  } else {
    const double a = e.fibre_angle_deg;
    in.mesh = e.mesh == "sheet" ? electro::make_sheet(e.mesh_size_x_mm, e.mesh_size_y_mm, e.mesh_spacing_mm, a)
                                : electro::make_slab(e.mesh_size_x_mm, e.mesh_size_y_mm, e.mesh_size_z_mm,
                                                     e.mesh_spacing_mm, a);
    in.models = {e.lv_cell_model};
    StimulusRegion box;
    box.kind = StimulusRegion::Kind::kBox;
    box.box_min_mm = Vec3::Constant(-1e-9);
    box.box_max_mm = Vec3::Constant(e.stimulus.box_size_mm + 1e-9);
    stim("corner_box", box, 0.0);
    const double sz = e.mesh == "sheet" ? 0.0 : e.mesh_size_z_mm;
    in.probes.push_back({"origin_corner", nearest_node(in.mesh, Vec3::Zero())});
    in.probes.push_back({"centre", nearest_node(in.mesh, Vec3(e.mesh_size_x_mm, e.mesh_size_y_mm, sz) / 2)});
    in.probes.push_back({"far_corner", nearest_node(in.mesh, Vec3(e.mesh_size_x_mm, e.mesh_size_y_mm, sz))});
  }
  return in;
}

// Appends one sample to the series: time, Vm at each probe, mean active tension over all nodes.
void sample_electro(std::vector<Series>& series, const electro::TissueSolver& tissue, const std::vector<Probe>& probes) {
  const ElectroMesh& m = tissue.mesh();
  series[0].values.push_back(tissue.time_ms() * 1e-3);
  for (std::size_t k = 0; k < probes.size(); ++k) series[k + 1].values.push_back(tissue.vm_mv()[probes[k].node]);
  double sum = 0;
  for (double t : tissue.active_tension_kpa()) sum += t;
  series.back().values.push_back(sum / static_cast<double>(m.node_count()));
}

// How a run is cut into beats and steps (step 3 of the file comment).
struct ElectroBeatPlan {
  double beat_ms;
  int max_beats;
  long steps_per_beat;
  long sample_every;
  double time_step_ms;
};

// Steps one beat, from the tissue's time to the step end nearest beat · beat_ms, sampling every
// plan.sample_every steps; ten times a beat polls cancel (throws Cancelled) and reports progress.
// Returns the steps taken.
long run_electro_beat(electro::TissueSolver& tissue, int beat, const ElectroBeatPlan& plan, std::vector<Series>& series,
                      const std::vector<Probe>& probes, const std::vector<std::map<std::string, double>>& beats,
                      RunControl& control) {
  const double t0 = tissue.time_ms();
  const double t_end = static_cast<double>(beat) * plan.beat_ms;
  const long steps_this_beat = std::max(1L, std::lround((t_end - t0) / plan.time_step_ms));
  long steps = 0;
  for (long n = 0; n < steps_this_beat; ++n) {
    tissue.step();
    ++steps;
    if ((n + 1) % plan.sample_every == 0) sample_electro(series, tissue, probes);
    if ((n + 1) % std::max(1L, plan.steps_per_beat / 10) == 0) {
      if (control.cancel_requested()) throw Cancelled();
      ProgressReport r;
      r.simulated_time_s = tissue.time_ms() * 1e-3;
      r.beat = beat;
      r.beats_total = plan.max_beats;
      r.fraction = (static_cast<double>(beat - 1) + static_cast<double>(n + 1) / static_cast<double>(plan.steps_per_beat)) / plan.max_beats;
      r.message = "electro";
      if (!beats.empty()) r.latest_beat_metrics = beats.back();
      control.on_progress(r);
    }
  }
  return steps;
}

// One beat's activation metrics, times relative to the beat's start t0; on the heart also per
// chamber (a chamber the imported heart lacks: NaN) and the AV activation delay.
std::map<std::string, double> electro_beat_metrics(const ElectroMesh& m, const electro::ActivationTracker& activation,
                                                   bool heart, int lv_domain, int la_domain, double t0) {
  std::map<std::string, double> bm;
  const DomainStats all = domain_stats(m, activation, -1, t0);
  bm["first_activation_ms"] = all.first_ms;
  bm["last_activation_ms"] = all.last_ms;
  bm["total_activation_time_ms"] = all.last_ms - all.first_ms;
  bm["activated_fraction"] = all.activated_fraction;
  bm["mean_apd90_ms"] = all.mean_apd90_ms;
  if (heart) {
    // A chamber the (imported) heart lacks reports NaN, i.e. -1 in metrics.json.
    DomainStats absent;
    absent.activated_fraction = std::numeric_limits<double>::quiet_NaN();
    const DomainStats lv = lv_domain >= 0 ? domain_stats(m, activation, lv_domain, t0) : absent;
    const DomainStats la = la_domain >= 0 ? domain_stats(m, activation, la_domain, t0) : absent;
    bm["lv_first_activation_ms"] = lv.first_ms;
    bm["lv_total_activation_time_ms"] = lv.last_ms - lv.first_ms;
    bm["lv_activated_fraction"] = lv.activated_fraction;
    bm["lv_mean_apd90_ms"] = lv.mean_apd90_ms;
    bm["la_first_activation_ms"] = la.first_ms;
    bm["la_total_activation_time_ms"] = la.last_ms - la.first_ms;
    bm["la_activated_fraction"] = la.activated_fraction;
    bm["la_mean_apd90_ms"] = la.mean_apd90_ms;
    bm["av_activation_delay_ms"] = lv.first_ms - la.first_ms;
  }
  return bm;
}

// Periodicity (step 4 of the file comment): the total activation time and the mean APD90 of
// beat bm both changed by less than tolerance relative to the previous beat a.
bool activation_repeats(const std::map<std::string, double>& a, const std::map<std::string, double>& bm,
                        double tolerance) {
  auto rel = [&](const char* k) { return std::abs(bm.at(k) - a.at(k)) / std::max(1e-12, std::abs(a.at(k))); };
  return rel("total_activation_time_ms") < tolerance && rel("mean_apd90_ms") < tolerance;
}

// With an output directory: the last beat's activation / APD90 / final Vm and tension fields,
// written by rank 0 only (every rank runs the whole serial EP); sets fields_written and a note.
void write_electro_outputs(RunResult& result, const electro::TissueSolver& tissue, RunControl& control) {
  const ElectroMesh& m = tissue.mesh();
  const auto dir = control.output_directory();
  result.metrics["fields_written"] = 0;
  // Every rank runs the whole (serial) electro scene; only rank 0 writes the shared file (ours:
  // the EP solve is not distributed over ranks).
  int mpi_ready = 0, rank = 0;
  MPI_Initialized(&mpi_ready);
  if (mpi_ready) MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (dir.empty()) {
    result.notes.push_back("no output directory: activation / APD fields not written");
  } else {
    if (rank == 0) {
      write_fields(dir, m,
                   {{"activation_time_ms", tissue.activation().activation_ms()},
                    {"apd90_ms", tissue.activation().apd_ms()},
                    {"vm_final_mv", tissue.vm_mv()},
                    {"active_tension_final_kpa", tissue.active_tension_kpa()}});
    }
    result.metrics["fields_written"] = 1;
    result.notes.push_back("activation time / APD90 of the last beat (NaN: not reached) in electro_fields.h5 + .xmf");
  }
}

}  // namespace

std::vector<geometry::TriMesh> load_electro_manifest(const std::string& path) {
  namespace fs = std::filesystem;
  const std::string field = "electro.mesh_manifest = '" + path + "'";
  std::error_code ec;
  const fs::path p(path);
  if (path.empty()) throw InputError("electro.mesh_manifest is empty: give the path of a mesh manifest (JSON)");
  if (!fs::exists(p, ec))
    throw InputError(field + ": no such file on the solver's machine (relative paths resolve against " +
                     fs::current_path(ec).string() + ")");
  if (!fs::is_regular_file(p, ec)) throw InputError(field + ": not a regular file");
  geometry::ImportedHeart heart;
  try {
    heart = geometry::load_manifest(p);
  } catch (const InputError& err) {
    throw InputError(field + ": " + err.what());
  }
  std::vector<geometry::TriMesh> bodies;
  std::string names;
  for (auto& b : heart.bodies) {
    names += (names.empty() ? "" : ", ") + ("'" + b.name + "'");
    if (b.name == geometry::kLvBody || b.name == geometry::kLaBody) bodies.push_back(std::move(b));
  }
  if (bodies.empty())
    throw InputError(field + ": no body named 'lv' or 'la' (the manifest has " + (names.empty() ? "no bodies" : names) +
                     "); the electro scene needs an LV and/or an LA");
  return bodies;
}

const std::vector<std::string>& electro_metric_names() {
  static const std::vector<std::string> names{
      "total_activation_time_ms", "first_activation_ms", "last_activation_ms", "activated_fraction",
      "mean_apd90_ms",            "nodes",               "cells",              "time_step_ms",
      "steps",                    "beats_simulated",     "reaction_wall_s",    "diffusion_wall_s",
      "fields_written",           "wall_time_s"};
  return names;
}

RunResult run_electro(const config::Scenario& scenario, RunControl& control) {
  const config::Electro& e = scenario.electro;
  const double period_ms = scenario.period_ms();
  const bool heart = e.mesh == "left_heart" || e.mesh == "manifest";

  // 1. mesh, cell models per domain, stimuli, probes
  ElectroInputs in = electro_inputs(scenario, heart, period_ms);
  const std::vector<Probe>& probes = in.probes;

  // 2. tissue
  electro::TissueOptions o = heart ? std::move(in.heart_options) : ep_tissue_options(scenario, in.models, in.stimuli);
  electro::TissueSolver tissue(std::move(in.mesh), std::move(o));
  const ElectroMesh& m = tissue.mesh();

  // 3. beats
  RunResult result;
  const double beat_ms = heart ? period_ms : e.end_time_ms;
  const int max_beats = heart ? scenario.beats : 1;
  // Steps per beat: the beat ends at the step end nearest to k * beat_ms (within dt / 2), so
  // the next beat's stimulus (at its midpoint time) never falls in this beat.
  const auto steps_per_beat = std::max(1L, std::lround(beat_ms / e.time_step_ms));
  const double sample_ms = scenario.outputs.time_series_interval_ms;
  const long sample_every = std::max(1L, std::lround(sample_ms / e.time_step_ms));
  const ElectroBeatPlan plan{beat_ms, max_beats, steps_per_beat, sample_every, e.time_step_ms};
  std::vector<Series> series{{"time_s", "s", {}}};
  for (const Probe& p : probes) series.push_back({"vm_" + p.name + "_mv", "mV", {}});
  series.push_back({"active_tension_mean_kpa", "kPa", {}});
  long steps = 0;
  int beat = 0;
  std::vector<std::map<std::string, double>> beats;
  for (beat = 1; beat <= max_beats; ++beat) {
    const double t0 = tissue.time_ms();
    tissue.activation().reset();
    for (auto& s : series) s.values.clear();  // keep the last beat's series (ours)
    sample_electro(series, tissue, probes);
    steps += run_electro_beat(tissue, beat, plan, series, probes, beats, control);
    const std::map<std::string, double> bm =
        electro_beat_metrics(m, tissue.activation(), heart, in.lv_domain, in.la_domain, t0);
    beats.push_back(bm);
    if (heart && beat >= 2 && scenario.periodicity_tolerance > 0 &&
        activation_repeats(beats[beats.size() - 2], bm, scenario.periodicity_tolerance)) {
      result.notes.push_back("periodic activation reached at beat " + std::to_string(beat));
      break;
    }
  }
  const int simulated = std::min(beat, max_beats);

  // 4. results
  // metrics.json has no NaN: -1 marks "never reached" (ours).
  for (auto& b : beats)
    for (auto& [k, v] : b)
      if (std::isnan(v)) v = -1.0;
  result.beats = beats;
  result.metrics = beats.back();
  result.metrics["nodes"] = static_cast<double>(m.node_count());
  result.metrics["cells"] = static_cast<double>(m.cell_count());
  result.metrics["time_step_ms"] = e.time_step_ms;
  result.metrics["steps"] = static_cast<double>(steps);
  result.metrics["beats_simulated"] = simulated;
  result.metrics["reaction_wall_s"] = tissue.reaction_seconds();
  result.metrics["diffusion_wall_s"] = tissue.diffusion_seconds();
  if (scenario.outputs.time_series) result.series = series;
  write_electro_outputs(result, tissue, control);
  return result;
}

}  // namespace systole::scene
