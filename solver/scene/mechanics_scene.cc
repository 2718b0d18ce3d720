#include "solver/scene/mechanics_scene.h"
#include "solver/scene/chamber_walls.h"
#include "solver/scene/h5_dataset.h"
#include "solver/scene/lv_wall_readings.h"
#include "solver/scene/pv_relations.h"

#include <hdf5.h>
#include <mpi.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/topology.h"
#include "solver/structure/contact.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::scene {
namespace {

using structure::ShellModel;
using structure::Vec3;

using structure::BodyGroup;

// The bodies of the scenario's structure.body, with their options, as one group advanced in
// lockstep with contact between its bodies (when there are several and structure.contact).
struct Bodies {
  std::unique_ptr<BodyGroup> group;
  std::vector<double> volume0_mm3;
  std::vector<std::vector<Vec3>> built_mm;  // per body, its initial (built) positions
  // Per body and node: 1 where the active tension acts, 0 in the passive annulus of the chamber
  // walls (structure.walls = "chamber").
  std::vector<std::vector<double>> active_share;
  std::size_t size() const { return group->body_count(); }
  const ShellModel& operator[](std::size_t k) const { return group->body(k); }
  ShellModel& operator[](std::size_t k) { return group->body(k); }
};

// The group of `models` (contact from structure.*), their initial volumes and positions, and
// an active share of 1 on every node unless `bodies` already holds one per body.
Bodies finish_bodies(Bodies bodies, std::vector<ShellModel> models, const config::Scenario& s) {
  if (bodies.active_share.empty())
    for (const auto& m : models) bodies.active_share.emplace_back(m.node_count(), 1.0);
  bodies.group = std::make_unique<BodyGroup>(std::move(models), scene::contact_options(s));
  for (std::size_t k = 0; k < bodies.size(); ++k) {
    bodies.volume0_mm3.push_back(bodies[k].cavity_volume_mm3());
    bodies.built_mm.push_back(bodies[k].positions_mm());
  }
  return bodies;
}

Bodies build_bodies(const config::Scenario& s) {
  const config::Structure& st = s.structure;
  structure::ShellOptions opt = structure_options(s, 0.0);
  opt.active_min_fibre_stretch = s.tissue.active_min_fibre_stretch;
  opt.active_cross_fibre_fraction = s.tissue.active_cross_fibre_fraction;
  const structure::ShellMaterials mat = structure::materials_from_config(s.tissue);
  std::vector<ShellModel> models;
  if (st.body == "sphere") {
    auto mesh = structure::icosphere(st.sphere_radius_mm, st.sphere_refinement, st.shell_thickness_mm,
                                     geometry::Tissue::kLvMyocardium, true);
    models.emplace_back(mesh, mat, opt);
  } else if (st.body == "sheet") {
    const int nx = std::max(3, static_cast<int>(std::lround(st.sheet_size_mm / st.sheet_edge_mm)) + 1);
    const int ny = std::max(3, static_cast<int>(std::lround(st.sheet_size_mm / (st.sheet_edge_mm * std::sqrt(3.0) / 2))) + 1);
    auto mesh = structure::flat_sheet(nx, ny, st.sheet_edge_mm, st.shell_thickness_mm,
                                      geometry::Tissue::kMitralLeaflet, Vec3::UnitX());
    // Clamped on its boundary (ours).
    const geometry::EdgeTopology topo(mesh);
    for (const auto& loop : geometry::boundary_loops(mesh, topo))
      for (auto i : loop) mesh.region[i] |= geometry::kAnchor;
    models.emplace_back(mesh, mat, opt);
  } else {  // left_heart (LV + LA), lv, mitral_leaflets
    const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
    opt.cavity_plane_z_mm = heart.plane.z_mm;
    if (st.body == "mitral_leaflets") {
      // Anchored at the annulus (the geometry tags it); the LV is on the +z side of the plane.
      for (auto name : {geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody}) {
        models.push_back(scene::body_shell(heart.body(name), mat, opt));  // pre-strained if it has a rest shape
        if (st.mitral_limiter)  // from the built, closed valve
          models.back().set_displacement_limit(-Vec3::UnitZ(), st.mitral_limit_mm, heart.body(name).position_mm);
      }
    } else {
      // The chamber walls as they read (structure.walls "structure") or as the coupled scenes build them.
      const bool chamber = st.walls == "chamber";
      const structure::ShellMaterials wall_mat = chamber ? chamber_wall_materials(s) : mat;
      const structure::ShellOptions wall_opt = chamber ? chamber_wall_options(s, heart.plane.z_mm) : opt;
      models.emplace_back(heart.body(geometry::kLvBody), wall_mat, wall_opt);
      if (st.body == "left_heart") models.emplace_back(heart.body(geometry::kLaBody), wall_mat, wall_opt);
      if (chamber) {
        Bodies bodies;
        for (const auto& m : models) {
          std::vector<std::int32_t> ep(m.node_count(), 0);
          clear_passive_annulus(m.stress_free_mesh(), s.electromechanics.passive_annulus_mm, ep);
          std::vector<double> share(ep.size());
          for (std::size_t i = 0; i < ep.size(); ++i) share[i] = ep[i] < 0 ? 0.0 : 1.0;
          bodies.active_share.push_back(std::move(share));
        }
        return finish_bodies(std::move(bodies), std::move(models), s);
      }
    }
  }
  return finish_bodies(Bodies{}, std::move(models), s);
}

// Per-node largest |edge strain| (a nodal field for ParaView).
std::vector<double> node_strain(const ShellModel& m) {
  std::vector<double> s(m.node_count(), 0.0);
  const auto eps = m.edge_strains();
  for (std::size_t k = 0; k < eps.size(); ++k) {
    const auto& sp = m.springs()[k];
    s[sp.i] = std::max(s[sp.i], std::abs(eps[k]));
    s[sp.j] = std::max(s[sp.j], std::abs(eps[k]));
  }
  return s;
}

// --- positions over time: HDF5 + XDMF ----------------------------------------------------------
void h5_write(hid_t file, const std::string& name, hid_t type, const void* data, hsize_t rows, hsize_t cols) {
  write_h5_dataset(file, name, type, data, rows, cols, "mechanics");
}

class PositionWriter {
 public:
  PositionWriter(const std::filesystem::path& dir, const Bodies& bodies) : dir_(dir) {
    std::filesystem::create_directories(dir);
    file_ = H5Fcreate((dir / "structure.h5").string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    if (file_ < 0) throw std::runtime_error("mechanics: cannot create " + (dir / "structure.h5").string());
    H5Gclose(H5Gcreate2(file_, "mesh", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5Gclose(H5Gcreate2(file_, "steps", H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const auto& m = bodies[k].stress_free_mesh();
      std::vector<std::int32_t> tri;
      for (const auto& t : m.tri) tri.insert(tri.end(), t.begin(), t.end());
      h5_write(file_, "mesh/" + bodies[k].name() + "_triangles", H5T_NATIVE_INT32, tri.data(), m.triangle_count(), 3);
    }
  }
  ~PositionWriter() {
    if (file_ >= 0) H5Fclose(file_);
  }
  PositionWriter(const PositionWriter&) = delete;
  PositionWriter& operator=(const PositionWriter&) = delete;

  void write(const Bodies& bodies, double time_ms) {
    const std::string step = "steps/" + std::to_string(times_.size());
    H5Gclose(H5Gcreate2(file_, step.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const ShellModel& b = bodies[k];
      std::vector<double> xyz;
      for (const auto& p : b.positions_mm()) xyz.insert(xyz.end(), {p.x(), p.y(), p.z()});
      const auto strain = node_strain(b);
      h5_write(file_, step + "/" + b.name() + "_positions_mm", H5T_NATIVE_DOUBLE, xyz.data(), b.node_count(), 3);
      h5_write(file_, step + "/" + b.name() + "_strain", H5T_NATIVE_DOUBLE, strain.data(), b.node_count(), 1);
    }
    times_.push_back(time_ms);
  }

  // The XDMF index (a temporal collection of per-body grids), written once at the end.
  void finish(const Bodies& bodies) {
    std::ofstream x(dir_ / "structure.xmf");
    x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n"
      << "  <Grid Name=\"structure\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
    for (std::size_t k = 0; k < times_.size(); ++k) {
      x << "   <Grid Name=\"step" << k << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
        << "    <Time Value=\"" << times_[k] << "\"/>\n";
      for (std::size_t b = 0; b < bodies.size(); ++b) {
        const std::string n = bodies[b].name();
        const auto nt = bodies[b].stress_free_mesh().triangle_count(), nn = bodies[b].node_count();
        x << "    <Grid Name=\"" << n << "\" GridType=\"Uniform\">\n"
          << "     <Topology TopologyType=\"Triangle\" NumberOfElements=\"" << nt << "\">\n"
          << "      <DataItem Dimensions=\"" << nt << " 3\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">structure.h5:/mesh/"
          << n << "_triangles</DataItem>\n     </Topology>\n"
          << "     <Geometry GeometryType=\"XYZ\">\n      <DataItem Dimensions=\"" << nn
          << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">structure.h5:/steps/" << k << "/" << n
          << "_positions_mm</DataItem>\n     </Geometry>\n"
          << "     <Attribute Name=\"strain\" AttributeType=\"Scalar\" Center=\"Node\">\n      <DataItem Dimensions=\"" << nn
          << "\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">structure.h5:/steps/" << k << "/" << n
          << "_strain</DataItem>\n     </Attribute>\n    </Grid>\n";
      }
      x << "   </Grid>\n";
    }
    x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  }

 private:
  std::filesystem::path dir_;
  hid_t file_ = -1;
  std::vector<double> times_;
};

double mean_abs_strain(const ShellModel& m) {
  const auto eps = m.edge_strains();
  double s = 0;
  for (double e : eps) s += std::abs(e);
  return eps.empty() ? 0 : s / static_cast<double>(eps.size());
}

// The metrics of the bodies' current state (mechanics_metric_names' state part, the per-body
// volumes and strains, and the LV wall's readings for bodies "lv" and "left_heart").
void add_state_metrics(const Bodies& bodies, const config::Structure& st, std::map<std::string, double>& m) {
  const ShellModel& main = bodies[0];
  const auto e = main.energies();
  m["volume_initial_ml"] = bodies.volume0_mm3.front() * 1e-3;
  m["volume_final_ml"] = main.cavity_volume_mm3() * 1e-3;
  m["volume_change_percent"] = 100 * (main.cavity_volume_mm3() / bodies.volume0_mm3.front() - 1);
  m["max_strain"] = main.max_abs_strain();
  m["mean_strain"] = mean_abs_strain(main);
  m["kinetic_energy_final_uj"] = e.kinetic_uj;
  m["elastic_energy_final_uj"] = e.elastic_uj;
  m["bending_energy_final_uj"] = e.bending_uj;
  m["contact_pairs_final"] = bodies.group->contact_stats().active;
  if (bodies.size() > 1 || st.body == "lv") {
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const ShellModel& b = bodies[k];
      m[b.name() + "_volume_initial_ml"] = bodies.volume0_mm3[k] * 1e-3;
      m[b.name() + "_volume_final_ml"] = b.cavity_volume_mm3() * 1e-3;
      m[b.name() + "_max_strain"] = b.max_abs_strain();
    }
  }
  if (st.body == "lv" || st.body == "left_heart") add_lv_wall_readings(main, "lv_", m);  // the LV is body 0
}

// --- protocol "pv_relations" ----------------------------------------------------------------
// The LV (body 0) loaded by a cavity pressure and a uniform active tension (times the active share).
void set_lv_loads(Bodies& bodies, double p_mmhg, double tau_kpa) {
  bodies[0].set_cavity_pressure(p_mmhg * units::kPaPerMmHg * 1e-3);
  std::vector<double> tau = bodies.active_share[0];
  for (double& v : tau) v *= tau_kpa;
  bodies[0].set_active_tension(std::move(tau));
}

// Ramps the LV's loads linearly from (p0, tau0) to (p1, tau1) over structure.pressure_ramp_ms in
// steps of at most 1/50 of it, then holds them, structure.output_interval_ms at a time, until the
// cavity volume changes by < 1e-6 of itself over an interval and the kinetic energy is < 1e-9 of
// the elastic (ours); returns the volume (ml). Throws std::runtime_error naming the point when the
// hold passes structure.end_time_ms.
double load_to_rest(Bodies& bodies, const config::Structure& st, double p0_mmhg, double p1_mmhg, double tau0_kpa,
                    double tau1_kpa, RunControl& control, long& substeps) {
  const double ramp = st.pressure_ramp_ms, step = ramp > 0 ? ramp / 50 : 0;
  for (double t = 0; t < ramp - 1e-12;) {
    if (control.cancel_requested()) throw Cancelled();
    const double te = std::min(ramp, t + step), w = 0.5 * (t + te) / ramp;
    set_lv_loads(bodies, p0_mmhg + w * (p1_mmhg - p0_mmhg), tau0_kpa + w * (tau1_kpa - tau0_kpa));
    substeps += bodies.group->advance(te - t).substeps;
    t = te;
  }
  set_lv_loads(bodies, p1_mmhg, tau1_kpa);
  double v = bodies[0].cavity_volume_mm3(), held = 0;
  for (;;) {
    if (control.cancel_requested()) throw Cancelled();
    substeps += bodies.group->advance(st.output_interval_ms).substeps;
    held += st.output_interval_ms;
    const double v_new = bodies[0].cavity_volume_mm3();
    const auto e = bodies[0].energies();
    const bool rest = std::abs(v_new - v) < 1e-6 * std::abs(v_new) && e.kinetic_uj < 1e-9 * std::abs(e.elastic_uj);
    v = v_new;
    if (rest) return v * 1e-3;
    if (held >= st.end_time_ms) {
      std::ostringstream m;
      m << "did not come to rest at " << p1_mmhg << " mmHg and " << tau1_kpa
        << " kPa within structure.end_time_ms = " << st.end_time_ms << " ms of hold (volume " << v * 1e-3
        << " ml, kinetic / elastic energy " << e.kinetic_uj / std::abs(e.elastic_uj)
        << "); raise structure.end_time_ms or structure.damping_per_ms";
      std::ostringstream place;
      place << "body lv, protocol pv_relations point " << p1_mmhg << " mmHg";
      throw InstabilityError("structure", place.str(), bodies[0].time_ms() * 1e-3, m.str());
    }
  }
}

// The fits of the measured points into `m`; a fit that cannot be made is a note, not an error (the
// points stay in pv_relations.csv).
void add_pv_fits(const std::vector<PvPoint>& ed, const std::vector<PvPoint>& es, RunResult& result) {
  auto& m = result.metrics;
  try {
    if (!ed.empty()) {
      const EdpvrFit f = fit_edpvr(ed);
      m["edpvr_v0_ml"] = f.v0_ml;
      m["edpvr_a_mmhg"] = f.a_mmhg;
      m["edpvr_beta_per_ml"] = f.beta_per_ml;
      m["edpvr_fit_rms_mmhg"] = f.rms_mmhg;
      m["edpvr_volume_at_max_ml"] = ed.back().volume_ml;
    }
  } catch (const std::invalid_argument& e) {
    result.notes.push_back(std::string("no EDPVR fit: ") + e.what());
  }
  try {
    if (!es.empty()) {
      const EspvrFit f = fit_espvr(es);
      m["espvr_e_es_mmhg_per_ml"] = f.e_es_mmhg_per_ml;
      m["espvr_v0_ml"] = f.v0_ml;
      m["espvr_fit_r2"] = f.r2;
      m["espvr_volume_at_min_ml"] = es.front().volume_ml;
      m["espvr_volume_at_max_ml"] = es.back().volume_ml;
    }
  } catch (const std::invalid_argument& e) {
    result.notes.push_back(std::string("no ESPVR fit: ") + e.what());
  }
}

void write_pv_points(const std::filesystem::path& dir, const std::vector<PvPoint>& ed, const std::vector<PvPoint>& es) {
  std::filesystem::create_directories(dir);
  std::ofstream csv(dir / "pv_relations.csv");
  csv << "relation,pressure_mmhg,volume_ml\n";
  for (const PvPoint& q : ed) csv << "edpvr," << q.pressure_mmhg << "," << q.volume_ml << "\n";
  for (const PvPoint& q : es) csv << "espvr," << q.pressure_mmhg << "," << q.volume_ml << "\n";
}

RunResult run_pv_relations(const config::Scenario& scenario, RunControl& control) {
  const config::Structure& st = scenario.structure;
  const auto start = std::chrono::steady_clock::now();
  Bodies bodies = build_bodies(scenario);
  const double dt0 = bodies.group->stable_step_ms();
  const int n = st.pv_points;
  std::vector<PvPoint> ed, es;
  long substeps = 0;
  const int total = (st.edpvr_max_mmhg > 0 ? n : 0) + (st.active_tension_kpa > 0 ? n : 0);
  int done = 0;
  auto progress = [&](const char* relation, double p_mmhg) {
    std::ostringstream what;
    what << "mechanics pv_relations: " << relation << " point at " << p_mmhg << " mmHg at rest";
    ProgressReport r;
    r.beat = 1;
    r.beats_total = 1;
    r.fraction = total > 0 ? static_cast<double>(++done) / total : 1;
    r.message = what.str();
    control.on_progress(r);
  };
  double p_mmhg = 0, tau_kpa = 0;
  if (st.edpvr_max_mmhg > 0) {
    ed.push_back({0, bodies[0].cavity_volume_mm3() * 1e-3});
    for (int k = 1; k <= n; ++k) {
      const double pk = st.edpvr_max_mmhg * k / n;
      ed.push_back({pk, load_to_rest(bodies, st, p_mmhg, pk, 0, 0, control, substeps)});
      p_mmhg = pk;
      progress("EDPVR", pk);
    }
  }
  for (int k = 0; st.active_tension_kpa > 0 && k < n; ++k) {
    const double pk = st.espvr_min_mmhg + (st.espvr_max_mmhg - st.espvr_min_mmhg) * k / (n - 1);
    es.push_back({pk, load_to_rest(bodies, st, p_mmhg, pk, tau_kpa, st.active_tension_kpa, control, substeps)});
    p_mmhg = pk;
    tau_kpa = st.active_tension_kpa;
    progress("ESPVR", pk);
  }
  RunResult result;
  const std::filesystem::path dir = control.output_directory();
  if (!dir.empty() && is_rank_zero()) {
    write_pv_points(dir, ed, es);
    result.notes.push_back("the measured points in pv_relations.csv (plot: client/systole-plot-pv)");
  }
  auto& m = result.metrics;
  add_state_metrics(bodies, st, m);  // the last point's state (the ESPVR's highest pressure, if any)
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  m["stable_step_initial_ms"] = dt0;
  m["stable_step_final_ms"] = bodies.group->stable_step_ms();
  m["substeps"] = static_cast<double>(substeps);
  m["nodes"] = static_cast<double>(bodies[0].node_count());
  m["node_substeps_per_s"] = wall_s > 0 ? static_cast<double>(substeps) * m["nodes"] / wall_s : 0;
  m["end_time_ms"] = bodies[0].time_ms();
  m["positions_written"] = 0;
  m["contact_pairs_max"] = bodies.group->contact_stats().active;
  m["contact_crossed_max"] = bodies.group->contact_stats().crossed;
  m["contact_min_gap_mm"] = st.contact_distance_mm;
  add_pv_fits(ed, es, result);
  m["wall_time_s"] = wall_s;
  return result;
}

}  // namespace

const std::vector<std::string>& mechanics_metric_names() {
  static const std::vector<std::string> names{
      "volume_initial_ml", "volume_final_ml", "volume_change_percent", "max_strain", "mean_strain",
      "kinetic_energy_final_uj", "elastic_energy_final_uj", "bending_energy_final_uj", "stable_step_initial_ms",
      "stable_step_final_ms", "substeps", "nodes", "node_substeps_per_s", "end_time_ms", "positions_written",
      "contact_pairs_final", "contact_pairs_max", "contact_crossed_max", "contact_min_gap_mm", "wall_time_s"};
  return names;
}

RunResult run_mechanics(const config::Scenario& scenario, RunControl& control) {
  const config::Structure& st = scenario.structure;
  if (st.protocol == "pv_relations") return run_pv_relations(scenario, control);
  const auto start = std::chrono::steady_clock::now();
  Bodies bodies = build_bodies(scenario);
  BodyGroup& group = *bodies.group;
  const double p_full_kpa = st.cavity_pressure_mmhg * units::kPaPerMmHg * 1e-3;
  // Mitral leaflets: normals towards the LA, so the LV-minus-LA pressure enters with a minus.
  const double p_sign = st.body == "mitral_leaflets" ? -1.0 : 1.0;
  auto ramp = [&](double t_ms) { return st.pressure_ramp_ms > 0 ? std::min(1.0, t_ms / st.pressure_ramp_ms) : 1.0; };
  auto set_loads = [&](double t_ms) {
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      bodies[k].set_cavity_pressure(p_sign * p_full_kpa * ramp(t_ms));
      if (st.active_tension_kpa > 0) {
        std::vector<double> tau = bodies.active_share[k];
        for (double& v : tau) v *= st.active_tension_kpa * ramp(t_ms);
        bodies[k].set_active_tension(std::move(tau));
      }
    }
  };

  const std::filesystem::path dir = control.output_directory();
  const bool write = st.write_positions && !dir.empty() && is_rank_zero();
  std::unique_ptr<PositionWriter> writer;
  if (write) writer = std::make_unique<PositionWriter>(dir, bodies);

  RunResult result;
  std::vector<Series> series{{"time_s", "s", {}}, {"pressure_mmhg", "mmHg", {}}};
  for (std::size_t k = 0; k < bodies.size(); ++k) series.push_back({bodies[k].name() + "_volume_ml", "ml", {}});
  const std::size_t first_extra = series.size();
  series.push_back({"max_strain", "", {}});
  series.push_back({"kinetic_energy_uj", "uJ", {}});
  series.push_back({"elastic_energy_uj", "uJ", {}});
  series.push_back({"bending_energy_uj", "uJ", {}});
  series.push_back({"contact_pairs", "", {}});
  int contact_max = 0, crossed_max = 0;
  double min_gap = st.contact_distance_mm;
  auto sample = [&](double t_ms) {
    series[0].values.push_back(t_ms * 1e-3);
    series[1].values.push_back(st.cavity_pressure_mmhg * ramp(t_ms));
    double strain = 0, ke = 0, el = 0, be = 0;
    for (std::size_t k = 0; k < bodies.size(); ++k) {
      const ShellModel& m = bodies[k];
      series[2 + k].values.push_back(m.cavity_volume_mm3() * 1e-3);
      strain = std::max(strain, m.max_abs_strain());
      const auto e = m.energies();
      ke += e.kinetic_uj;
      el += e.elastic_uj;
      be += e.bending_uj;
    }
    const auto& cs = group.contact_stats();
    series[first_extra].values.push_back(strain);
    series[first_extra + 1].values.push_back(ke);
    series[first_extra + 2].values.push_back(el);
    series[first_extra + 3].values.push_back(be);
    series[first_extra + 4].values.push_back(cs.active);
    contact_max = std::max(contact_max, cs.active);
    crossed_max = std::max(crossed_max, cs.crossed);
    if (cs.active > 0) min_gap = std::min(min_gap, cs.min_gap_mm);
    if (writer) writer->write(bodies, t_ms);
  };

  const double dt0 = group.stable_step_ms();
  sample(0);
  const double load_step_ms = st.pressure_ramp_ms > 0 ? st.pressure_ramp_ms / 50 : st.end_time_ms;
  const int steps = std::max(1, static_cast<int>(std::ceil(st.end_time_ms / st.output_interval_ms - 1e-9)));
  long substeps = 0;
  double nodes = 0;
  for (std::size_t k = 0; k < bodies.size(); ++k) nodes += static_cast<double>(bodies[k].node_count());
  double t = 0;
  const auto loop_start = std::chrono::steady_clock::now();
  for (int k = 1; k <= steps; ++k) {
    if (control.cancel_requested()) throw Cancelled();
    const double t_next = std::min(st.end_time_ms, k * st.output_interval_ms);
    // Loads held over each load step at their value at its middle (ours); during the ramp a load
    // step is at most 1/50 of it, so a coarse output interval does not jolt the body.
    for (double ts = t; ts < t_next - 1e-12;) {
      const double te = ts < st.pressure_ramp_ms ? std::min(t_next, ts + load_step_ms) : t_next;
      set_loads(0.5 * (ts + te));
      substeps += group.advance(te - ts).substeps;
      ts = te;
    }
    t = t_next;
    sample(t);
    ProgressReport report;
    report.simulated_time_s = t * 1e-3;
    report.beat = 1;
    report.beats_total = 1;
    report.fraction = t / st.end_time_ms;
    report.message = "mechanics t = " + std::to_string(t) + " ms";
    control.on_progress(report);
  }
  const double loop_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - loop_start).count();
  if (writer) {
    writer->finish(bodies);
    result.notes.push_back("node positions and strains at every outer step in structure.h5 (+ structure.xmf for ParaView)");
  } else if (st.write_positions && dir.empty()) {
    result.notes.push_back("positions were requested but the caller gave no output directory: none written");
  }

  auto& m = result.metrics;
  add_state_metrics(bodies, st, m);
  m["stable_step_initial_ms"] = dt0;
  m["stable_step_final_ms"] = group.stable_step_ms();
  m["substeps"] = static_cast<double>(substeps);
  m["nodes"] = nodes;
  m["node_substeps_per_s"] = loop_s > 0 ? static_cast<double>(substeps) * nodes / loop_s : 0;
  m["end_time_ms"] = t;
  m["positions_written"] = writer ? 1 : 0;
  m["contact_pairs_max"] = contact_max;
  m["contact_crossed_max"] = crossed_max;
  m["contact_min_gap_mm"] = min_gap;
  if (st.body == "mitral_leaflets") {
    // Largest displacement of a leaflet node towards the LA (-z) from the built valve, to compare
    // with the limiter.
    double towards_la = 0;
    for (std::size_t k = 0; k < bodies.size(); ++k)
      for (std::size_t i = 0; i < bodies[k].node_count(); ++i)
        towards_la = std::max(towards_la, bodies.built_mm[k][i].z() - bodies[k].positions_mm()[i].z());
    m["leaflet_displacement_towards_la_mm"] = towards_la;
  }
  if (scenario.outputs.time_series) result.series = std::move(series);
  m["wall_time_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace systole::scene
