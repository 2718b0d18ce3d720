#include "solver/scene/fsei/series.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/scene/fsei/chamber_cells.h"
#include "solver/scene/fsei/wall_shear.h"

namespace systole::scene::fsei {

using geometry::Vec3;

SamplingSites::SamplingSites(const config::Scenario& s, const CoupledHeart& h) : probes(chamber_probes(s, h.heart)) {
  const geometry::LeftHeart& heart = h.heart;
  mitral_tips_mm = heart.plane.mitral_centre_mm + heart.layout.mitral_coaptation_depth_mm * heart.lv_axis_direction;
  aortic_tips_mm = heart.plane.aortic_centre_mm - heart.layout.cusp_coaptation_height_mm * heart.lv_axis_direction;
  mitral_disk_mm = std::min(5.0, 0.5 * heart.plane.mitral_radius_mm);
  aortic_disk_mm = std::min(5.0, 0.5 * heart.plane.aortic_radius_mm);
  aortic_orifice_mm2 = std::numbers::pi * heart.plane.aortic_radius_mm * heart.plane.aortic_radius_mm;
  mitral_orifice_mm2 = std::numbers::pi * heart.plane.mitral_radius_mm * heart.plane.mitral_radius_mm;
  lv_markers = marker_body_named(h.markers, geometry::kLvBody);
  aorta_markers = marker_body_named(h.markers, geometry::kAortaBody);
  plane_markers = marker_body_named(h.markers, geometry::kValvularPlaneBody);
  link_of_marker_body.assign(h.markers.bodies().size(), -1);
  for (std::size_t li = 0; li < h.links.size(); ++li)
    link_of_marker_body[static_cast<std::size_t>(h.links[li].marker_body)] = static_cast<int>(li);
  lv_side = heart.lv_axis_direction.z() > 0 ? 1 : -1;
  outflow_axis = (heart.outflow.end_mm - heart.outflow.start_mm).normalized();
}

double SampleContext::pressure_mmhg(ProbeIndex probe) {
  if (!pressures_) pressures_ = probe_pressures(h.fluid, sites.probes, h.s.fsei.probe_radius_mm);
  const std::vector<double>& p = *pressures_;
  return (p[probe] - p[kProbeOuter]) * h.scales.mmhg_per_unit;
}

// The immersed boundary's leak seen at the walls (ours): −Σ (u(X_b) − V_b)·n_b A_b over each
// body's active markers; through the rigid plane −Σ (u(X_b) − V_b)·a A_b, a the LV's axis (base →
// apex): positive from the LV side towards the atrium's and the aortic root's. A tight wall has 0;
// lv_volume_balance_ml is their integral when the slip at the markers is the whole leak.
double SampleContext::slip_flux_ml_s(SlipBody body) {
  if (!slip_) {
    const fluid::Velocity& u = h.fluid.velocity();
    const std::vector<Vec3> ub = h.forcing.transfer().interpolate(ibm::ConstVelocityView{u.u, u.v, u.w});
    const ibm::MarkerArrays& ma = h.markers.markers();
    double lv_out = 0, aorta_out = 0, plane_out = 0;
    for (std::size_t mk = 0; mk < ma.size(); ++mk) {
      if (!h.markers.active(mk)) continue;
      const Vec3 slip = ub[mk] - ma.velocity[mk];
      if (ma.body[mk] == sites.lv_markers) lv_out -= slip.dot(ma.normal[mk]) * ma.area[mk];
      else if (ma.body[mk] == sites.aorta_markers) aorta_out -= slip.dot(ma.normal[mk]) * ma.area[mk];
      else if (ma.body[mk] == sites.plane_markers) plane_out -= slip.dot(h.heart.lv_axis_direction) * ma.area[mk];
    }
    slip_ = std::array<double, 3>{lv_out, aorta_out, plane_out};
  }
  return (*slip_)[body] * h.scales.ml_s_per_unit;
}

const ibm::WallShear& SampleContext::wall_shear() {
  if (!wall_shear_) wall_shear_ = h.fluid_module.wall_shear();
  return *wall_shear_;
}

const diagnostics::WallKinematics& SampleContext::lv_kinematics() {
  if (!kinematics_)
    kinematics_ = diagnostics::wall_kinematics(h.heart.body(geometry::kLvBody), h.group.body(kLv).positions_mm(),
                                               h.heart.lv_axis_direction);
  return *kinematics_;
}

namespace {

// The kinetic energy of the chambers' blood (the seed's "kinetic energy in the heart"; the box's
// is kinetic_energy_mj): the cells inside the LV and the LA closed by the valvular plane
// (chamber_cells.h), as the box's: a box mean × the box.
double heart_kinetic_energy_mj(SampleContext& c) {
  CoupledHeart& h = c.h;
  const grid::Slabs& sl = h.fluid.slabs();
  const grid::Grid& gg = sl.grid();
  const int kb = sl.k_begin(), kc = sl.k_count();
  const std::vector<char> in_heart =
      heart_chambers_cells(h.group.body(kLv).positions_mm(), h.group.body(kLv).stress_free_mesh().tri,
                           h.group.body(kLa).positions_mm(), h.group.body(kLa).stress_free_mesh().tri, h.heart.plane.z_mm,
                           c.sites.lv_side, gg.nx(), gg.ny(), kb, kc, gg.dx() * kDmMm, gg.dy() * kDmMm, gg.dz() * kDmMm);
  const fluid::Velocity& u = h.fluid.velocity();
  double sum = 0;  // Σ |u|² over the chambers' cells, the fluid's own per-cell reading (its faces at (i, j, k))
  for (int k = 0; k < kc; ++k)
    for (int j = 0; j < gg.ny(); ++j)
      for (int i = 0; i < gg.nx(); ++i) {
        const std::size_t cell = (static_cast<std::size_t>(k) * gg.ny() + j) * gg.nx() + i;
        if (in_heart[cell]) sum += u.u(i, j, k) * u.u(i, j, k) + u.v(i, j, k) * u.v(i, j, k) + u.w(i, j, k) * u.w(i, j, k);
      }
  MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, sl.comm());
  return 0.5 * sum / static_cast<double>(gg.cells()) * h.scales.kinetic_mj_per_unit;
}

// The aortic cusps' largest wall shear stress (the seed's "> 3 Pa at the tips at peak systole").
double cusps_wss_max_pa(SampleContext& c) {
  const ibm::WallShear& w = c.wall_shear();
  const ibm::MarkerArrays& ma = c.h.markers.markers();
  double most = 0;
  for (std::size_t mk = 0; mk < ma.size(); ++mk) {
    const int li = c.sites.link_of_marker_body[static_cast<std::size_t>(ma.body[mk])];
    if (li < 0 || !c.h.markers.active(mk)) continue;
    const std::size_t shell = c.h.links[static_cast<std::size_t>(li)].shell;
    if (deformable_bodies()[shell].rfind("aortic_cusp_", 0) == 0)
      most = std::max(most, marker_wss_pa(w, mk, c.h.scales.pa_per_unit));
  }
  return most;
}

double disk_flux_ml_s(SampleContext& c, const Vec3& centre_mm, double radius_mm) {
  return disk_flux(c.h.fluid, centre_mm, radius_mm) * c.h.scales.ml_s_per_unit;
}

}  // namespace

// The table. Order: the result's columns. Ejection is the flow through the aortic orifice towards
// the aorta (-z), filling through the mitral orifice into the LV (+z); tip velocities along the
// flow (into the LV, into the aorta). The afterload's flow (ours): through the descending aorta's
// cross-section where the Darcy region starts (a disk of the outflow's radius normal to z, +
// towards the outlet), its pressure at the descending aorta's probe (the root's reads low inside
// the jet); with them the outlet's resistance.
const std::vector<SeriesSpec>& series_table() {
  using G = SeriesGroup;
  using C = SampleContext;
  static const std::vector<SeriesSpec> table{
      {"time_s", "s", "t_ms", "", G::kCore, 1e-3, [](C& c) { return c.t_ms; }},
      {"lv_pressure_mmhg", "mmHg", "p_lv", "p_lv_mmhg", G::kCore, 1, [](C& c) { return c.pressure_mmhg(kProbeLv); }},
      {"la_pressure_mmhg", "mmHg", "p_la", "p_la_mmhg", G::kCore, 1, [](C& c) { return c.pressure_mmhg(kProbeLa); }},
      {"aortic_root_pressure_mmhg", "mmHg", "p_ao", "p_ao_mmhg", G::kCore, 1,
       [](C& c) { return c.pressure_mmhg(kProbeAorticRoot); }},
      {"lv_volume_ml", "ml", "v_lv", "v_lv_ml", G::kCore, 1,
       [](C& c) { return c.h.group.body(kLv).cavity_volume_mm3() * kMlPerMm3; }},
      {"la_volume_ml", "ml", "v_la", "v_la_ml", G::kCore, 1,
       [](C& c) { return c.h.group.body(kLa).cavity_volume_mm3() * kMlPerMm3; }},
      {"aortic_flow_ml_s", "ml/s", "q_ao", "q_ao_ml_s", G::kCore, 1,
       [](C& c) {
         return -disk_flux(c.h.fluid, c.h.heart.plane.aortic_centre_mm, c.h.heart.plane.aortic_radius_mm) *
                c.h.scales.ml_s_per_unit;
       }},
      {"mitral_flow_ml_s", "ml/s", "q_mi", "q_mi_ml_s", G::kCore, 1,
       [](C& c) { return disk_flux_ml_s(c, c.h.heart.plane.mitral_centre_mm, c.h.heart.plane.mitral_radius_mm); }},
      {"kinetic_energy_mj", "mJ", "ke", "ke_mj", G::kCore, 1,
       [](C& c) { return c.h.fluid.diagnostics().kinetic_energy * c.h.scales.kinetic_mj_per_unit; }},
      {"heart_kinetic_energy_mj", "mJ", "ke_heart", "", G::kHeartKineticEnergy, 1, heart_kinetic_energy_mj},
      {"lv_twist_deg", "deg", "twist", "", G::kCore, 1, [](C& c) { return c.lv_kinematics().twist_deg; }},
      {"lv_longitudinal_strain", "", "gls", "", G::kCore, 1, [](C& c) { return c.lv_kinematics().longitudinal_strain; }},
      {"lv_circumferential_strain", "", "gcs", "", G::kCore, 1,
       [](C& c) { return c.lv_kinematics().circumferential_strain; }},
      {"mitral_tip_velocity_m_s", "m/s", "u_mitral_tips", "", G::kCore, 1,
       [](C& c) { return disk_mean_w(c.h.fluid, c.sites.mitral_tips_mm, c.sites.mitral_disk_mm) * kUmMmPerMs; }},
      {"aortic_tip_velocity_m_s", "m/s", "u_aortic_tips", "", G::kCore, 1,
       [](C& c) { return -disk_mean_w(c.h.fluid, c.sites.aortic_tips_mm, c.sites.aortic_disk_mm) * kUmMmPerMs; }},
      {"lv_wall_slip_flux_ml_s", "ml/s", "lv_wall_slip", "lv_slip_ml_s", G::kWallSlip, 1,
       [](C& c) { return c.slip_flux_ml_s(C::kSlipLv); }},
      {"aorta_wall_slip_flux_ml_s", "ml/s", "aorta_wall_slip", "aorta_slip_ml_s", G::kWallSlip, 1,
       [](C& c) { return c.slip_flux_ml_s(C::kSlipAorta); }},
      {"valvular_plane_slip_flux_ml_s", "ml/s", "plane_slip", "plane_slip_ml_s", G::kWallSlip, 1,
       [](C& c) { return c.slip_flux_ml_s(C::kSlipPlane); }},
      {"aortic_outlet_flow_ml_s", "ml/s", "q_out", "q_out_ml_s", G::kOutlet, 1,
       [](C& c) {
         return (c.sites.outflow_axis.z() > 0 ? 1.0 : -1.0) *
                disk_flux(c.h.fluid, c.h.heart.outflow.start_mm, c.h.heart.outflow.radius_mm) * c.h.scales.ml_s_per_unit;
       }},
      {"descending_aorta_pressure_mmhg", "mmHg", "p_desc", "p_desc_mmhg", G::kDescendingAorta, 1,
       [](C& c) { return c.pressure_mmhg(kProbeDescendingAorta); }},
      {"aortic_cusps_wss_max_pa", "Pa", "wss_cusps", "", G::kCore, 1, cusps_wss_max_pa},
  };
  return table;
}

SeriesRecorder::SeriesRecorder(const config::Scenario& s, CoupledHeart& h)
    : s_(s),
      h_(h),
      sites_(s, h),
      values_(series_table().size()),
      wss_phase_(shell_node_total(h.group), 1e-3 * s.period_ms(), kWssPhaseBins, 1) {
  present_.fill(true);
  // the afterload's flow needs a descending aorta along z, the chambers' kinetic energy an LV
  // whose long axis runs along z (chamber_cells.h)
  present_[static_cast<std::size_t>(SeriesGroup::kOutlet)] = std::abs(sites_.outflow_axis.z()) > 0.99;
  present_[static_cast<std::size_t>(SeriesGroup::kHeartKineticEnergy)] = std::abs(h.heart.lv_axis_direction.z()) > 0.99;
}

void SeriesRecorder::resume(const StateArchive& state) {
  const auto& table = series_table();
  for (const SeriesSpec& spec : table)  // (the core series must be there: StateArchive::get throws)
    if (spec.group != SeriesGroup::kCore && !state.has("series/" + spec.state_key))
      present_[static_cast<std::size_t>(spec.group)] = false;
  const long samples = static_cast<long>(state.get("series/t_ms").size());
  for (std::size_t k = 0; k < table.size(); ++k)
    if (wanted(table[k])) values_[k] = state.get("series/" + table[k].state_key, samples);
  // (a checkpoint of an earlier version has no phase-average accumulators: they start here)
  const double t_ms = state.scalar("scene/time_ms");
  wss_phase_from_ms_ = state.has("scene/wss_phase/beat") ? 0.0 : t_ms;
  if (wss_phase_from_ms_ == 0) wss_phase_.import_state(state, "scene/wss_phase/");
}

void SeriesRecorder::sample() {
  const double t_ms = h_.fluid_module.time_ms();
  const auto& table = series_table();
  SampleContext c(h_, sites_, t_ms);
  for (std::size_t k = 0; k < table.size(); ++k)
    if (wanted(table[k])) values_[k].push_back(table[k].sample(c));
  for (std::size_t k = 1; k < table.size(); ++k)
    if (wanted(table[k]) && !std::isfinite(values_[k].back()))
      throw InstabilityError("fsei", "diagnostics", 1e-3 * t_ms,
                             "a chamber pressure, volume, flow, wall strain, tip velocity or wall shear stress is not finite");
  check_slow_runaway();
  std::vector<double> wss_nodes;
  wss_nodes.reserve(shell_node_total(h_.group));
  for (const std::vector<double>& v : node_wss_pa(h_, c.wall_shear())) wss_nodes.insert(wss_nodes.end(), v.begin(), v.end());
  wss_phase_.add(1e-3 * t_ms, wss_nodes);
}

const std::vector<double>& SeriesRecorder::values(const std::string& name) const {
  const auto& table = series_table();
  for (std::size_t k = 0; k < table.size(); ++k)
    if (table[k].name == name && wanted(table[k])) return values_[k];
  throw std::logic_error("fsei: no series " + name + " in this run");
}

double SeriesRecorder::mean_speed_m_s() const {
  const double blood_m3 = 1e-6 * (latest("lv_volume_ml") + latest("la_volume_ml"));
  return blood_m3 > 0 ? std::sqrt(2e-3 * latest("kinetic_energy_mj") / (s_.fluid.density_kg_per_m3 * blood_m3)) : 0.0;
}

std::string SeriesRecorder::progress_fields() const {
  std::ostringstream m;
  m.precision(7);
  const auto& table = series_table();
  for (std::size_t k = 0; k < table.size(); ++k)
    if (wanted(table[k]) && !table[k].progress_key.empty()) m << " " << table[k].progress_key << " " << values_[k].back();
  return m.str();
}

std::vector<Series> SeriesRecorder::named() const {
  std::vector<Series> out;
  const auto& table = series_table();
  for (std::size_t k = 0; k < table.size(); ++k) {
    if (!wanted(table[k])) continue;
    std::vector<double> v = values_[k];
    if (table[k].result_scale != 1)
      for (double& x : v) x = table[k].result_scale * x;
    out.push_back({table[k].name, table[k].unit, std::move(v)});
  }
  return out;
}

std::vector<std::string> SeriesRecorder::absent_notes() const {
  std::vector<std::string> notes;
  if (!has(SeriesGroup::kWallSlip))
    notes.push_back("resumed from a checkpoint without the wall-slip series: lv_wall_slip_flux_ml_s, "
                    "aorta_wall_slip_flux_ml_s, valvular_plane_slip_flux_ml_s, lv_wall_slip_volume_ml and "
                    "valvular_plane_slip_volume_ml are not reported");
  if (!has(SeriesGroup::kOutlet))
    notes.push_back(std::abs(sites_.outflow_axis.z()) > 0.99
                        ? "resumed from a checkpoint without the outlet's flow: aortic_outlet_flow_ml_s is not reported"
                        : "the descending aorta's outlet is not along z: aortic_outlet_flow_ml_s is not reported");
  if (!has(SeriesGroup::kDescendingAorta))
    notes.push_back("resumed from a checkpoint without the descending aorta's pressure: "
                    "descending_aorta_pressure_mmhg is not reported");
  if (!has(SeriesGroup::kHeartKineticEnergy))
    notes.push_back(std::abs(h_.heart.lv_axis_direction.z()) > 0.99
                        ? "resumed from a checkpoint without the chambers' kinetic energy: "
                          "heart_kinetic_energy_mj is not reported"
                        : "the LV's long axis does not run along z: heart_kinetic_energy_mj is not reported");
  return notes;
}

void SeriesRecorder::export_state(StateArchive& a) const {
  const auto& table = series_table();
  for (std::size_t k = 0; k < table.size(); ++k)
    if (wanted(table[k]) && values_[k].size() == values_[0].size()) a.put("series/" + table[k].state_key, values_[k]);
  wss_phase_.export_state(a, "scene/wss_phase/");
}

// The slow-runaway guard (ours): energy let in by the coupling over tens of ms raises the blood's
// kinetic energy far above the beat's without a 10-fold jump in one fluid step or a collapse of
// the step (the fluid's own guards). The box's kinetic energy as a mean speed of the LV's and
// LA's blood is set against the streams that carry it: the largest mean velocity through a
// valve's orifice so far (flow / the orifice's area; ml/s per mm² = m/s). In a beat the first
// stays below the second (at most 0.80 of it through the ejection at 180 bpm, 0.69 at 70 bpm;
// docs/notes/fsei-notebook.md); above fsei.abort_mean_speed_m_s and more than
// fsei.abort_mean_speed_orifice_ratio times the orifices' the run stops. Computed from the
// series, so a resumed run guards as a straight one.
void SeriesRecorder::check_slow_runaway() const {
  const config::Fsei& fs = s_.fsei;
  double orifice_m_s = 0;
  for (double q : values("aortic_flow_ml_s")) orifice_m_s = std::max(orifice_m_s, std::abs(q) / sites_.aortic_orifice_mm2);
  for (double q : values("mitral_flow_ml_s")) orifice_m_s = std::max(orifice_m_s, std::abs(q) / sites_.mitral_orifice_mm2);
  const double speed = mean_speed_m_s();
  if (!(speed > fs.abort_mean_speed_m_s && speed > fs.abort_mean_speed_orifice_ratio * orifice_m_s)) return;
  const std::vector<double>& ke = values("kinetic_energy_mj");
  const std::vector<double>& t_ms = times_ms();
  std::ostringstream place, what;
  place << "the blood of the LV and LA (" << latest("lv_volume_ml") + latest("la_volume_ml")
        << " ml), fastest cell " << h_.fluid.fastest_cell();
  what << "kinetic energy " << ke.back() << " mJ in the box is a mean speed of " << speed
       << " m/s over the chambers' blood, above fsei.abort_mean_speed_m_s = " << fs.abort_mean_speed_m_s
       << " and above fsei.abort_mean_speed_orifice_ratio = " << fs.abort_mean_speed_orifice_ratio
       << " x the largest mean velocity through a valve's orifice so far (" << orifice_m_s
       << " m/s): energy out of proportion to the streams";
  // how fast it came (an abrupt blow-up within a few ms or a slow rise over tens): the latest
  // earlier sample at half the energy or less
  std::size_t half = ke.size() - 1;
  while (half > 0 && ke[half] > 0.5 * ke.back()) --half;
  if (ke[half] <= 0.5 * ke.back())
    what << "; it doubled in the last " << t_ms.back() - t_ms[half] << " ms (" << ke[half] << " mJ at t = "
         << 1e-3 * t_ms[half] << " s)";
  else
    what << "; it was above half this at every earlier sample (since t = " << 1e-3 * t_ms.front() << " s)";
  throw InstabilityError("fluid", place.str(), 1e-3 * t_ms.back(), what.str());
}

}  // namespace systole::scene::fsei
