#include "solver/scene/fsei_scene.h"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <limits>
#include <numbers>
#include <optional>
#include <span>
#include <sstream>
#include <unordered_map>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/coupling/body_group_module.h"
#include "solver/coupling/electro_module.h"
#include "solver/coupling/fluid_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/diagnostics/beat_metrics.h"
#include "solver/diagnostics/phase_average.h"
#include "solver/diagnostics/kinematics.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/tiling.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/ibm/mls.h"
#include "solver/lumped/activation.h"
#include "solver/scene/chamber_cells.h"
#include "solver/scene/chamber_walls.h"
#include "solver/scene/electro_scene.h"
#include "solver/scene/fsei_checkpoint.h"
#include "solver/scene/fsei_fields.h"
#include "solver/scene/h5_dataset.h"
#include "solver/structure/contact.h"
#include "solver/structure/prestress.h"
#include "solver/structure/shell.h"

namespace systole::scene {
namespace {

using geometry::Vec3;

// The seed's scales (MODEL.md §3): lengths in d_m, velocities in U_m, times in d_m/U_m.
constexpr double kDmMm = 1000 * units::kSeedLength_m;          // 24 mm
constexpr double kUmMmPerMs = units::kSeedVelocity_m_s;        // 0.6 mm/ms
constexpr double kTimeScaleMs = kDmMm / kUmMmPerMs;            // 40 ms
constexpr double kMlPerMm3 = 1e-3;
// The coarsest grid the valves allow (ours): the aortic orifice must span this many cells of
// the largest spacing, or the closed cusps and the open orifice are not told apart.
constexpr double kMinCellsAcrossAorticOrifice = 8;

// A module whose clock is another's shifted by a constant (ours): EP runs from the LA stimulus,
// the scene from the LV stimulus, av_delay later.
class ShiftedClock final : public coupling::Module {
 public:
  ShiftedClock(coupling::Module& inner, double offset_ms) : inner_(inner), offset_ms_(offset_ms) {}
  const std::string& name() const override { return inner_.name(); }
  double time_ms() const override { return inner_.time_ms() - offset_ms_; }
  double offset_ms() const { return offset_ms_; }
  double max_step_ms() const override { return inner_.max_step_ms(); }
  void step(double dt_ms) override { inner_.step(dt_ms); }
  void save() override { inner_.save(); }
  void restore() override { inner_.restore(); }

 private:
  coupling::Module& inner_;
  double offset_ms_;
};

// The scene's clock as a stage of its own (fsi with fsei.coupling_order = structure_first):
// it reaches an interval's end before the shells, so the prescribed tension the shells get is
// the one at the interval's end, as with the fluid's clock in the fluid-first order.
class SceneClock final : public coupling::Module {
 public:
  explicit SceneClock(double t_ms) : t_ms_(t_ms) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_ms_; }
  double max_step_ms() const override { return 1e9; }  // no limit of its own: one step per interval
  void step(double dt_ms) override { t_ms_ += dt_ms; }
  void save() override { saved_ms_ = t_ms_; }
  void restore() override { t_ms_ = saved_ms_; }

 private:
  std::string name_ = "scene clock";
  double t_ms_, saved_ms_ = 0;
};

// A sub-mesh with the same nodes and the triangles `keep` selects (the LA wall and its vein caps
// become separate marker bodies that share the shell's nodes).
geometry::TriMesh select_triangles(const geometry::TriMesh& mesh, const std::string& name,
                                   const std::function<bool(std::size_t)>& keep) {
  geometry::TriMesh out;
  out.name = name;
  out.kind = mesh.kind;
  out.position_mm = mesh.position_mm;
  out.region = mesh.region;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (!keep(t)) continue;
    out.tri.push_back(mesh.tri[t]);
    out.tissue.push_back(mesh.tissue[t]);
    out.thickness_mm.push_back(mesh.thickness_mm[t]);
    out.fibre.push_back(mesh.fibre[t]);
  }
  return out;
}

// A marker body driven by one shell: the tiling map from the shell's nodes to the body's tiled
// nodes, and the loads' way back.
struct Link {
  int marker_body = -1;
  std::size_t shell = 0;
  geometry::TilingMap map;
  bool cap = false;  // a pulmonary-vein cap (switched on and off)
};

// A sphere of cells whose mean pressure is a chamber's pressure.
struct Probe {
  std::string name;
  Vec3 centre_mm;
};

// Mean pressure (nondimensional) over the cells whose centres lie within radius of each probe.
// Collective. Throws InputError when a probe holds no cell centre.
std::vector<double> probe_pressures(const fluid::FluidSolver& fluid, const std::vector<Probe>& probes,
                                    double radius_mm) {
  const grid::Slabs& slabs = fluid.slabs();
  const grid::Grid& g = slabs.grid();
  const grid::CellField& p = fluid.pressure();
  const std::size_t n = probes.size();
  std::vector<double> sum(2 * n, 0.0);
  const double r = radius_mm / kDmMm;
  for (std::size_t q = 0; q < n; ++q) {
    const Vec3 c = probes[q].centre_mm / kDmMm;
    const int k0 = std::max(slabs.k_begin(), static_cast<int>(std::floor((c.z() - r) / g.dz())));
    const int k1 = std::min(slabs.k_begin() + slabs.k_count() - 1, static_cast<int>(std::ceil((c.z() + r) / g.dz())));
    const int j0 = std::max(0, static_cast<int>(std::floor((c.y() - r) / g.dy())));
    const int j1 = std::min(g.ny() - 1, static_cast<int>(std::ceil((c.y() + r) / g.dy())));
    const int i0 = std::max(0, static_cast<int>(std::floor((c.x() - r) / g.dx())));
    const int i1 = std::min(g.nx() - 1, static_cast<int>(std::ceil((c.x() + r) / g.dx())));
    for (int k = k0; k <= k1; ++k)
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          const Vec3 x(g.x(grid::Location::cell, i), g.y(grid::Location::cell, j), g.z(grid::Location::cell, k));
          if ((x - c).norm() > r) continue;
          sum[2 * q] += p(i, j, k - slabs.k_begin());
          sum[2 * q + 1] += 1;
        }
  }
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), static_cast<int>(sum.size()), MPI_DOUBLE, MPI_SUM, slabs.comm());
  std::vector<double> mean(n);
  for (std::size_t q = 0; q < n; ++q) {
    if (sum[2 * q + 1] == 0)
      throw InputError("fsei.probe_radius_mm = " + std::to_string(radius_mm) + " mm: the " + probes[q].name +
                       " probe holds no cell centre; allowed: at least half the grid spacing");
    mean[q] = sum[2 * q] / sum[2 * q + 1];
  }
  return mean;
}

// The z-velocity summed over the z-faces of the disk of `radius_mm` around `centre_mm` on the
// z-face plane nearest to its z, and the number of those faces (nondimensional). Collective.
std::array<double, 2> disk_sum_w(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const grid::Slabs& slabs = fluid.slabs();
  const grid::Grid& g = slabs.grid();
  const Vec3 c = centre_mm / kDmMm;
  const double r = radius_mm / kDmMm;
  const int k = static_cast<int>(std::lround(c.z() / g.dz()));
  std::array<double, 2> sum{0, 0};
  if (k >= slabs.k_begin() && k < slabs.k_begin() + slabs.k_count()) {
    const grid::ZFaceField& w = fluid.velocity().w;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        const double dx = g.x(grid::Location::z_face, i) - c.x(), dy = g.y(grid::Location::z_face, j) - c.y();
        if (dx * dx + dy * dy <= r * r) sum[0] += w(i, j, k - slabs.k_begin()), sum[1] += 1;
      }
  }
  MPI_Allreduce(MPI_IN_PLACE, sum.data(), 2, MPI_DOUBLE, MPI_SUM, slabs.comm());
  return sum;
}

// Volume flux (nondimensional, + along +z) through that disk. Collective.
double disk_flux(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const grid::Grid& g = fluid.slabs().grid();
  return disk_sum_w(fluid, centre_mm, radius_mm)[0] * g.dx() * g.dy();
}

// Mean z-velocity (nondimensional) over that disk: a Doppler-like sample volume (ours: one face
// layer). Collective; 0 when the disk holds no face.
double disk_mean_w(const fluid::FluidSolver& fluid, const Vec3& centre_mm, double radius_mm) {
  const std::array<double, 2> sum = disk_sum_w(fluid, centre_mm, radius_mm);
  return sum[1] > 0 ? sum[0] / sum[1] : 0.0;
}

// Whether a point lies inside the aorta (ours, for the initial pressure field): within reach_mm
// of an aorta node and on the inner side of the nearest node's inward normal, but not on the
// LV's side of the plane (z >= plane_z) within two orifice radii of the aortic axis (there the
// nearest node is the root's ring, whose normal points at the LV's outflow tract). A bucket
// grid of cell reach_mm.
class AortaInterior {
 public:
  AortaInterior(const geometry::TriMesh& aorta, const geometry::ValvularPlane& plane, double reach_mm)
      : x_(aorta.position_mm),
        n_(geometry::node_normals(aorta)),
        plane_z_mm_(plane.z_mm),
        axis_mm_(plane.aortic_centre_mm),
        outflow_tract_mm_(2 * plane.aortic_radius_mm),
        cell_mm_(reach_mm) {
    lo_ = x_.front();
    for (const Vec3& p : x_) lo_ = lo_.cwiseMin(p);
    for (std::size_t i = 0; i < x_.size(); ++i) buckets_[key(index(x_[i]))].push_back(static_cast<std::int32_t>(i));
  }
  bool inside(const Vec3& p_mm) const {
    if (p_mm.z() >= plane_z_mm_ && (p_mm - axis_mm_).head<2>().norm() < outflow_tract_mm_) return false;
    const std::array<long, 3> k = index(p_mm);
    double best = cell_mm_ * cell_mm_;
    std::int32_t nearest = -1;
    for (int a = -1; a <= 1; ++a)
      for (int b = -1; b <= 1; ++b)
        for (int c = -1; c <= 1; ++c) {
          const auto it = buckets_.find(key({k[0] + a, k[1] + b, k[2] + c}));
          if (it == buckets_.end()) continue;
          for (std::int32_t i : it->second) {
            const double d2 = (x_[static_cast<std::size_t>(i)] - p_mm).squaredNorm();
            if (d2 < best) best = d2, nearest = i;
          }
        }
    if (nearest < 0) return false;
    const auto i = static_cast<std::size_t>(nearest);
    return (p_mm - x_[i]).dot(n_[i]) > 0;
  }

 private:
  std::array<long, 3> index(const Vec3& p) const {
    return {static_cast<long>(std::floor((p.x() - lo_.x()) / cell_mm_)),
            static_cast<long>(std::floor((p.y() - lo_.y()) / cell_mm_)),
            static_cast<long>(std::floor((p.z() - lo_.z()) / cell_mm_))};
  }
  static long key(const std::array<long, 3>& k) { return ((k[0] + 1024) * 2048 + (k[1] + 1024)) * 2048 + (k[2] + 1024); }
  std::vector<Vec3> x_, n_;
  double plane_z_mm_;
  Vec3 axis_mm_;
  double outflow_tract_mm_, cell_mm_;
  Vec3 lo_;
  std::unordered_map<long, std::vector<std::int32_t>> buckets_;
};

// The seed's aorta pre-tension (MODEL.md §1: "an external force providing a ground pressure of
// 60 mmHg in the aortic root"), ours in detail: an outer pressure p on the aorta's wall, the
// follower load p A n_in / 3 on each node of each loaded triangle (n_in into the lumen: the load
// pushes the wall inwards; structure::pressure_nodal_forces), at the given positions. The
// triangles of the Darcy outflow (all three nodes tagged kOutflow) carry none: there the blood's
// pressure falls to the outer fluid's, and an outer load would squeeze the tube shut. Adds to f (mN).
void add_outer_pressure_loads(const geometry::TriMesh& aorta, const std::vector<Vec3>& x_mm, double pressure_kpa,
                              std::vector<Vec3>& f_mn) {
  const std::vector<Vec3> load = structure::pressure_nodal_forces(aorta, x_mm, pressure_kpa, geometry::kOutflow);
  for (std::size_t i = 0; i < f_mn.size(); ++i) f_mn[i] += load[i];
}

}  // namespace

GridPoints fsei_grid_points(const config::Scenario& s) {
  const std::string& r = s.fsei.resolution;
  if (r == "custom") return {s.fluid.nx, s.fluid.ny, s.fluid.nz};
  // A preset's points are the issue's for the 140-mm box; a box of another height keeps the
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

std::vector<std::map<std::string, double>> fsei_beat_metrics(const std::vector<Series>& series, double period_ms,
                                                             double blood_density_kg_per_m3, const std::string& scene) {
  if (!(blood_density_kg_per_m3 > 0))
    throw std::invalid_argument("fsei_beat_metrics: blood_density_kg_per_m3 must be > 0, got " +
                                std::to_string(blood_density_kg_per_m3));
  auto find = [&](const std::string& name) -> const std::vector<double>& {
    for (const Series& x : series)
      if (x.name == name) return x.values;
    throw std::invalid_argument("fsei_beat_metrics: no series '" + name + "'");
  };
  const std::vector<double>& t_s = find("time_s");
  for (const Series& x : series)
    if (x.values.size() != t_s.size())
      throw std::invalid_argument("fsei_beat_metrics: series '" + x.name + "' has " + std::to_string(x.values.size()) +
                                  " samples, time_s " + std::to_string(t_s.size()));
  struct Peak {
    const char* series;
    const char* metric;
    enum { kLargest, kSmallest, kLargestMagnitude } kind;
  };
  const Peak peaks[] = {{"kinetic_energy_mj", "kinetic_energy_max_mj", Peak::kLargest},
                        {"lv_twist_deg", "lv_twist_peak_deg", Peak::kLargestMagnitude},
                        {"lv_longitudinal_strain", "lv_longitudinal_strain_min", Peak::kSmallest},
                        {"lv_circumferential_strain", "lv_circumferential_strain_min", Peak::kSmallest},
                        {"mitral_tip_velocity_m_s", "mitral_tip_velocity_max_m_s", Peak::kLargest},
                        {"aortic_tip_velocity_m_s", "aortic_tip_velocity_max_m_s", Peak::kLargest},
                        {"aortic_cusps_wss_max_pa", "aortic_cusps_wss_max_pa", Peak::kLargest},
                        {"la_volume_ml", "la_volume_max_ml", Peak::kLargest},
                        {"la_volume_ml", "la_volume_min_ml", Peak::kSmallest},
                        {"la_pressure_mmhg", "la_pressure_max_mmhg", Peak::kLargest}};
  std::vector<std::map<std::string, double>> out;
  const double period_s = 1e-3 * period_ms, tol_s = 1e-9;
  if (t_s.empty() || !(period_s > 0)) return out;
  for (int b = 1; b * period_s <= t_s.back() + tol_s; ++b) {
    const double start = (b - 1) * period_s, stop = b * period_s;
    std::size_t i0 = 0;
    while (i0 < t_s.size() && t_s[i0] < start - tol_s) ++i0;
    std::size_t i1 = i0;
    while (i1 < t_s.size() && t_s[i1] <= stop + tol_s) ++i1;
    // only whole beats: samples at both ends
    if (i1 - i0 < 3 || std::abs(t_s[i0] - start) > tol_s || std::abs(t_s[i1 - 1] - stop) > tol_s) continue;
    const std::size_t n = i1 - i0;
    auto window = [&](const std::string& name) {
      const std::span<const double> w(find(name).data() + i0, n);
      for (std::size_t i = 0; i < n; ++i)
        if (!std::isfinite(w[i]))
          throw InstabilityError(scene, "beat " + std::to_string(b) + " series " + name, t_s[i0 + i],
                                 "a non-finite sample");
      return w;
    };
    diagnostics::BeatSamples bs;
    bs.time_s = window("time_s");
    bs.lv_volume_ml = window("lv_volume_ml");
    bs.lv_pressure_mmhg = window("lv_pressure_mmhg");
    bs.aortic_pressure_mmhg = window("aortic_root_pressure_mmhg");
    bs.mitral_flow_ml_s = window("mitral_flow_ml_s");
    bs.aortic_flow_ml_s = window("aortic_flow_ml_s");
    bs.beat_start_s = start;
    bs.period_s = period_s;
    // a valve is open while its flow exceeds 5 % of its peak: the leaflets' motion and the
    // closed valves' leak move a few % of the peak flow back and forth (ours)
    bs.valve_threshold_fraction = 0.05;
    // ... and the flow must stay across that level for 2 % of the period (17 ms at 70 bpm): the
    // leaflets' flutter moves the flow through it for a few ms around an opening (ours)
    bs.valve_min_dwell_fraction = 0.02;
    // End-diastole is the window's start (ours): the scene starts every beat at the activation
    // with the valves closed (MODEL.md §1), not at the first mitral closure in the window
    // (which, after a weak E wave, is a closure of a closed valve's back-and-forth flow: EF −5 %
    // for the first ejecting run, docs/fsei.md session 11).
    bs.end_diastole_at_beat_start = true;
    std::map<std::string, double> m = diagnostics::to_map(diagnostics::compute_beat_metrics(bs));
    // the chambers' kinetic energy (a series of runs since session 33): its peak where the series is there
    for (const Series& x : series)
      if (x.name == "heart_kinetic_energy_mj") {
        const std::span<const double> v = window(x.name);
        m["heart_kinetic_energy_max_mj"] = *std::max_element(v.begin(), v.end());
      }
    for (const Peak& p : peaks) {
      const std::span<const double> v = window(p.series);
      double best = v[0];
      for (double x : v)
        if (p.kind == Peak::kLargest ? x > best : p.kind == Peak::kSmallest ? x < best : std::abs(x) > std::abs(best))
          best = x;
      m[p.metric] = best;
    }
    // The seed's twist is read at end-systole (MODEL.md §8: ≈ 17°): the twist at the aortic closure, where the beat
    // has one; the peak above is over the whole beat.
    if (const auto close = m.find("aortic_valve_close_phase"); close != m.end())
      m["lv_twist_end_systole_deg"] = diagnostics::value_at(bs.time_s, window("lv_twist_deg"), start + close->second * period_s);
    // The aortic flow's reversal after its peak (ours): where the valve's threshold reading above (5 % of the peak
    // flow, held for 2 % of the period) takes a slow tail of the ejection for the closure, the reversal is the
    // ejection's end (docs/fsei.md session 32: 0.347-0.348 T on three grids where the threshold read 0.308-0.341 T).
    {
      const std::span<const double> q = bs.aortic_flow_ml_s;
      const std::size_t i_peak = std::max_element(q.begin(), q.end()) - q.begin();
      if (const auto t_rev = diagnostics::first_crossing(bs.time_s.subspan(i_peak), q.subspan(i_peak), 0.0,
                                                         diagnostics::Crossing::kDownward))
        m["aortic_flow_reversal_phase"] = (*t_rev - start) / period_s;
    }
    // An open valve as a clinician reads it (ours, after the Gorlin and Hakki formulas with a discharge
    // coefficient of 1): the mean gradient across it (upstream − downstream chamber) and the effective orifice
    // area A = Q̄ / sqrt(2 Δp̄ / ρ) over its open interval (its opening to its closure, or to the beat's end).
    // Healthy adults: mitral 4-6 cm² at a mean gradient < 2 mmHg, a severe stenosis < 1 cm²; aortic 3-4 cm², a
    // severe stenosis < 1 cm² or a mean gradient > 40 mmHg (Baumgartner et al., J Am Soc Echocardiogr 22:1-23,
    // 2009). A closure before the opening is the previous beat's flow ending (the mitral's A wave): the interval
    // then runs to the beat's end. The area is left out when the valve did not open or the mean gradient or flow
    // is not positive.
    auto read_open_valve = [&](const std::string& valve, std::span<const double> flow, std::span<const double> upstream,
                               std::span<const double> downstream) {
      const auto open = m.find(valve + "_valve_open_phase");
      if (open == m.end()) return;
      const double t_open = start + open->second * period_s;
      const auto close = m.find(valve + "_valve_close_phase");
      const double t_close =
          close != m.end() && close->second > open->second ? start + close->second * period_s : stop;
      if (!(t_close > t_open)) return;
      std::vector<double> t, q, dp;  // the open interval, its ends interpolated
      auto push = [&](double at) {
        t.push_back(at);
        q.push_back(diagnostics::value_at(bs.time_s, flow, at));
        dp.push_back(diagnostics::value_at(bs.time_s, upstream, at) - diagnostics::value_at(bs.time_s, downstream, at));
      };
      push(t_open);
      for (std::size_t i = 0; i < n; ++i)
        if (bs.time_s[i] > t_open && bs.time_s[i] < t_close) {
          t.push_back(bs.time_s[i]);
          q.push_back(flow[i]);
          dp.push_back(upstream[i] - downstream[i]);
        }
      push(t_close);
      const double q_mean_ml_s = diagnostics::time_average(t, q), dp_mean_mmhg = diagnostics::time_average(t, dp);
      m[valve + "_mean_gradient_mmhg"] = dp_mean_mmhg;
      if (dp_mean_mmhg > 0 && q_mean_ml_s > 0) {
        const double speed_m_s = std::sqrt(2 * dp_mean_mmhg * units::kPaPerMmHg / blood_density_kg_per_m3);
        m[valve + "_effective_orifice_area_cm2"] = q_mean_ml_s / (100 * speed_m_s);  // ml/s / (cm/s)
      }
    };
    read_open_valve("mitral", bs.mitral_flow_ml_s, window("la_pressure_mmhg"), bs.lv_pressure_mmhg);
    read_open_valve("aortic", bs.aortic_flow_ml_s, bs.lv_pressure_mmhg, bs.aortic_pressure_mmhg);
    m["beat"] = b;
    m["beat_start_s"] = start;
    for (const auto& [key, value] : m)
      if (!std::isfinite(value))
        throw InstabilityError(scene, "beat " + std::to_string(b) + " metric " + key, stop, "a non-finite beat metric");
    out.push_back(std::move(m));
  }
  return out;
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

RunResult run_fsei(const config::Scenario& s, RunControl& control) {
  const bool with_ep = s.scene == "fsei";
  const config::Fsei& fs = s.fsei;
  const double period_ms = s.period_ms();
  const double sync_ms = fs.sync_step_ms;
  const double end_ms = fs.end_time_ms > 0 ? fs.end_time_ms : s.beats * period_ms;
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

  // 0. a checkpoint to resume from (RunControl::checkpoint_directory, fsei_checkpoint.h): one
  //    of this scenario (its fingerprint; the run's length, outputs and intervals may differ)
  const std::filesystem::path checkpoint_root = control.checkpoint_directory();
  const std::string fingerprint = scenario_fingerprint(s);
  std::optional<std::filesystem::path> resume_from;
  StateArchive resumed;
  if (!checkpoint_root.empty()) {
    resume_from = CheckpointDirectory(checkpoint_root).resumable();
    if (resume_from) {
      std::string stored;
      resumed = read_state_file(*resume_from / "state.h5", stored);
      check_fingerprint(*resume_from, stored, fingerprint);
      const double t_resumed = resumed.scalar("scene/time_ms");
      if (t_resumed > end_ms + 1e-9)
        throw InputError("the checkpoint in " + resume_from->string() + " is at t = " + std::to_string(t_resumed) +
                         " ms, past this run's end (fsei.end_time_ms or beats: " + std::to_string(end_ms) +
                         " ms); ask for a longer run or remove the checkpoint directory");
    }
  }

  // 1. the grid of the preset, and the heart in its box (build_left_heart checks the fit)
  const GridPoints pts = fsei_grid_points(s);
  const grid::Grid g({pts.nx - 1, pts.ny - 1, pts.nz - 1, s.fluid.box_x_mm / kDmMm, s.fluid.box_y_mm / kDmMm,
                      s.fluid.box_z_mm / kDmMm});
  const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
  {
    const double h_mm = std::max({g.dx(), g.dy(), g.dz()}) * kDmMm;
    const double d_mm = 2 * heart.plane.aortic_radius_mm;
    if (d_mm < kMinCellsAcrossAorticOrifice * h_mm) {
      const double h_max = d_mm / kMinCellsAcrossAorticOrifice;
      std::ostringstream m;
      m << "fsei.resolution = \"" << fs.resolution << "\" (" << pts.nx << " x " << pts.ny << " x " << pts.nz
        << " points) is too coarse for the valves: the aortic orifice (diameter " << d_mm << " mm) spans "
        << d_mm / h_mm << " cells of " << h_mm << " mm; at least " << kMinCellsAcrossAorticOrifice
        << " are needed (spacing <= " << h_max << " mm: at least "
        << static_cast<int>(std::ceil(s.fluid.box_x_mm / h_max)) + 1 << " x "
        << static_cast<int>(std::ceil(s.fluid.box_y_mm / h_max)) + 1 << " x "
        << static_cast<int>(std::ceil(s.fluid.box_z_mm / h_max)) + 1 << " points)";
      throw InputError(m.str());
    }
  }


  // 2. the shells of the deformable bodies (the chamber walls as in scene electromechanics)
  const config::Electromechanics& em = s.electromechanics;
  const structure::ShellMaterials materials = chamber_wall_materials(s);
  const structure::ShellOptions wall = chamber_wall_options(s, heart.plane.z_mm);
  const structure::ShellOptions other = structure_options(s, heart.plane.z_mm);
  const std::vector<std::string_view> deformable{geometry::kLvBody,           geometry::kLaBody,
                                                 geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody,
                                                 geometry::kAorticCuspBodies[0], geometry::kAorticCuspBodies[1],
                                                 geometry::kAorticCuspBodies[2], geometry::kAortaBody};
  std::vector<structure::ShellModel> models;
  for (auto name : deformable) {
    const bool chamber = name == geometry::kLvBody || name == geometry::kLaBody;
    // (a mitral leaflet with a rest opening starts pre-strained at its built, closed shape)
    models.push_back(body_shell(heart.body(name), materials, chamber ? wall : other));
    const bool mitral = name == geometry::kMitralAnteriorBody || name == geometry::kMitralPosteriorBody;
    // The seed's limiter (no chordae): towards the atrium, -z, from the built (closed) valve; it
    // holds over the phases [0, structure.mitral_limiter_end_phase) of every beat
    // (set_mitral_limiter below; the seed's in systole only, ours by default all the time).
    if (mitral && s.structure.mitral_limiter)
      models.back().set_displacement_limit(-Vec3::UnitZ(), s.structure.mitral_limit_mm, heart.body(name).position_mm);
    // The open cusps kept off the sinus wall (structure.aortic_cusp_radius_limit, ours).
    const bool cusp = std::find(std::begin(geometry::kAorticCuspBodies), std::end(geometry::kAorticCuspBodies), name) !=
                      std::end(geometry::kAorticCuspBodies);
    if (cusp && s.structure.aortic_cusp_radius_limit > 0)
      models.back().set_radial_limit(heart.plane.aortic_centre_mm, heart.lv_axis_direction,
                                     s.structure.aortic_cusp_radius_limit * heart.plane.aortic_radius_mm);
    // The Darcy outlet held (fsei.aortic_outlet_held, ours): anchored to the plane alone, the
    // descending aorta's free end drifted 3 mm into the box's wall by 111 ms (docs/fsei.md).
    if (name == geometry::kAortaBody && fs.aortic_outlet_held) {
      const geometry::TriMesh& aorta = heart.body(name);
      std::vector<std::int32_t> outlet;
      for (std::size_t i = 0; i < aorta.node_count(); ++i)
        if (aorta.region[i] & geometry::kOutflow) outlet.push_back(static_cast<std::int32_t>(i));
      models.back().fix_nodes(outlet);
    }
  }
  structure::BodyGroup group(std::move(models), contact_options(s));
  constexpr std::size_t kLv = 0, kLa = 1;
  const auto kAorta = static_cast<std::size_t>(
      std::find(deformable.begin(), deformable.end(), geometry::kAortaBody) - deformable.begin());

  // The aorta's ground pressure (the seed's pre-tension, MODEL.md §1): the blood inside the aorta
  // starts at fsei.aortic_pressure_mmhg above the rest of the box, and an outer pressure as
  // large holds its wall (add_outer_pressure_loads), so the built aorta is in equilibrium at
  // t = 0 and the closed aortic valve carries the pressure from the first step. (Ours: the
  // outer load stays on; the wall's elasticity adds to it as the aorta fills.) The fluid's
  // pressure is incremental, so the offset persists: the outer fluid stays the reference.
  const bool aorta_prestressed = fs.aortic_pretension == "prestress" && fs.aortic_pressure_mmhg > 0;
  // The wall's share of the ground pressure (fsei.aortic_prestress_fraction, ours): 1 with
  // prestress, 0 with the outer load; the outer load carries the rest.
  const double wall_share = aorta_prestressed ? fs.aortic_prestress_fraction : 0.0;
  const double aortic_outer_kpa = (1 - wall_share) * fs.aortic_pressure_mmhg * units::kPaPerMmHg * 1e-3;
  // fsei.aortic_pretension = prestress (ours): instead of the outer load, the aorta's springs are
  // shortened so that its built shape is in equilibrium with the wall's share of the ground
  // pressure inside (on every triangle outside the Darcy outlet, as the outer load) and none
  // outside; anchors and the held outlet take the reactions (structure/prestress.h). With a ramp
  // the rest lengths go from the built ones to these over fsei.aortic_pressure_ramp_ms (set in the
  // loads transfer), as the outer load does.
  std::vector<double> aorta_built_rest_mm, aorta_prestress_rest_mm;
  std::optional<structure::Prestress> aorta_prestress;
  if (aorta_prestressed) {
    structure::ShellModel& aorta = group.body(kAorta);
    const double p_kpa = wall_share * fs.aortic_pressure_mmhg * units::kPaPerMmHg * 1e-3;
    aorta_prestress = structure::membrane_prestress(
        aorta, structure::pressure_nodal_forces(aorta.stress_free_mesh(), aorta.positions_mm(), -p_kpa, geometry::kOutflow));
    aorta_prestress_rest_mm = aorta_prestress->rest_length_mm;
    for (const auto& sp : aorta.springs()) aorta_built_rest_mm.push_back(sp.rest_length_mm);
    if (fs.aortic_pressure_ramp_ms == 0) aorta.set_rest_lengths_mm(aorta_prestress_rest_mm);
  }
  // The rest lengths of the ramp at time t (ms).
  auto aorta_rest_lengths_at = [&](double t_ms) {
    const double r = std::min(1.0, t_ms / fs.aortic_pressure_ramp_ms);
    std::vector<double> l0(aorta_built_rest_mm.size());
    for (std::size_t k = 0; k < l0.size(); ++k)
      l0[k] = aorta_built_rest_mm[k] + r * (aorta_prestress_rest_mm[k] - aorta_built_rest_mm[k]);
    return l0;
  };

  // 3. the markers: the rigid valvular plane, every deformable body (the LA wall and its vein
  //    caps separately); one-sided loads from the blood inside the chambers and the aorta,
  //    two-sided on the leaflets and the caps
  ibm::Markers markers(g);
  {
    ibm::BodyOptions plane;
    plane.mm_per_unit = kDmMm;
    plane.rigid = true;
    plane.sides = ibm::Sides::two;
    markers.add_body(heart.body(geometry::kValvularPlaneBody), std::string(geometry::kValvularPlaneBody), plane);
  }
  std::vector<Link> links;
  // The tiling level of a body (fsei.marker_tiling): "longest_edge" is ibm::Markers' rule (every
  // tile edge <= 0.7 h); "mean_edge" (ours) tiles so that the mean tile edge is <= 0.7 h (the
  // seed's "marker spacing ≈ 0.7 h") and the longest <= h (no marker coarser than the grid):
  // a mesh with a few long edges is not over-refined everywhere.
  const double h_mm = markers.h() * kDmMm;
  auto tiling_level = [&](const geometry::TriMesh& mesh) {
    if (fs.marker_tiling == "longest_edge") return 0;  // Markers' automatic choice
    double sum = 0, longest = 0;
    for (const auto& t : mesh.tri)
      for (int k = 0; k < 3; ++k) {
        const double l = (mesh.position_mm[t[k]] - mesh.position_mm[t[(k + 1) % 3]]).norm();
        sum += l;
        longest = std::max(longest, l);
      }
    const double mean = sum / (3.0 * static_cast<double>(mesh.tri.size()));
    return std::max({1, static_cast<int>(std::ceil(longest / h_mm - 1e-12)),
                     static_cast<int>(std::ceil(mean / (0.7 * h_mm) - 1e-12))});
  };
  auto link = [&](const geometry::TriMesh& mesh, const std::string& name, std::size_t shell, bool two_sided, bool cap) {
    ibm::BodyOptions o;
    o.mm_per_unit = kDmMm;
    o.tiling_level = tiling_level(mesh);
    o.rigid = false;
    o.sides = two_sided ? ibm::Sides::two : ibm::Sides::one;
    Link l;
    l.marker_body = markers.add_body(mesh, name, o);
    l.shell = shell;
    l.map = geometry::tiling_map(mesh, markers.bodies()[static_cast<std::size_t>(l.marker_body)].tiling_level);
    l.cap = cap;
    links.push_back(std::move(l));
  };
  for (std::size_t b = 0; b < deformable.size(); ++b) {
    const geometry::TriMesh& mesh = heart.body(deformable[b]);
    const std::string name(deformable[b]);
    if (b == kLa) {
      auto is_cap = [&](std::size_t t) { return mesh.tissue[t] == geometry::Tissue::kVeinOstium; };
      link(select_triangles(mesh, name, [&](std::size_t t) { return !is_cap(t); }), name, b, false, false);
      const geometry::TriMesh caps = select_triangles(mesh, "pv_caps", is_cap);
      if (!caps.tri.empty()) link(caps, "pv_caps", b, true, true);
    } else {
      link(mesh, name, b, mesh.kind == geometry::BodyKind::kLeaflet, false);
    }
  }
  // 4. the fluid: blood at rest, the Darcy afterload around the end of the descending aorta,
  //    on slabs split by the planes' work (fsei.slab_split = "balanced", ours: the immersed
  //    boundary's work sits where the markers are; with equal blocks one of 2 ranks waited half its
  //    time), so built after the markers
  if (fs.slab_split != "balanced" && fs.slab_split != "uniform")
    throw InputError("fsei.slab_split = \"" + fs.slab_split + "\" is not one of: balanced, uniform");
  std::vector<double> marker_z(markers.size());
  for (std::size_t q = 0; q < markers.size(); ++q) marker_z[q] = markers.markers().position[q].z();
  const grid::Slabs slabs(g, MPI_COMM_WORLD, fs.slab_split == "balanced" ? slab_plane_weights(g, marker_z) : std::vector<double>{});
  fluid::FluidParameters fp;
  fp.reynolds = units::kSeedVelocity_m_s * units::kSeedLength_m / s.fluid.kinematic_viscosity_m2_per_s;
  fp.cfl = s.fluid.cfl;
  fp.cfl_rule = s.fluid.cfl_rule;
  fp.subgrid_model = s.fluid.subgrid_model;
  fp.subgrid_constant = s.fluid.subgrid_constant;
  fp.max_dt = std::min(s.fluid.max_dt_ms, sync_ms) / kTimeScaleMs;
  fp.darcy_permeability = s.fluid.darcy_permeability;
  // A stable step below 1e-3 of the largest (velocities 1000x the design's) is a blow-up (ours:
  // a run with 10 forcing passes crawled at 21 ms for ten minutes instead of stopping).
  fp.abort_min_dt = 1e-3 * fp.max_dt;
  {
    const auto& o = heart.outflow;
    // The cylinder's bounding box: its radius reaches r sqrt(1 - a_i^2) along axis i.
    const Vec3 a = (o.end_mm - o.start_mm).normalized();
    Vec3 pad;
    for (int i = 0; i < 3; ++i) pad[i] = o.radius_mm * std::sqrt(std::max(0.0, 1 - a[i] * a[i]));
    const Vec3 lo = o.start_mm.cwiseMin(o.end_mm) - pad;
    const Vec3 hi = o.start_mm.cwiseMax(o.end_mm) + pad;
    fp.darcy_regions.push_back({lo.x() / kDmMm, hi.x() / kDmMm, lo.y() / kDmMm, hi.y() / kDmMm, lo.z() / kDmMm,
                                hi.z() / kDmMm});
  }
  fluid::FluidSolver fluid(slabs, fp);

  // The blood inside the aorta starts at the ground pressure (step 2's comment), unless ramped.
  double aorta_initial_ml = 0;  // the volume started at the ground pressure (a note)
  if (fs.aortic_pressure_mmhg > 0 && fs.aortic_pressure_ramp_ms == 0) {
    const geometry::TriMesh& aorta = heart.body(geometry::kAortaBody);
    const AortaInterior interior(aorta, heart.plane, 0.75 * s.geometry.aortic_root_diameter_mm);
    const double p0 = fs.aortic_pressure_mmhg * units::kPaPerMmHg /
                      (s.fluid.density_kg_per_m3 * units::kSeedVelocity_m_s * units::kSeedVelocity_m_s);
    long inside_cells = 0;
    fluid.set_pressure([&](double x, double y, double z) {
      if (!interior.inside(Vec3(x, y, z) * kDmMm)) return 0.0;
      ++inside_cells;
      return p0;
    });
    long all = 0;
    MPI_Allreduce(&inside_cells, &all, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
    aorta_initial_ml = static_cast<double>(all) * g.dx() * g.dy() * g.dz() * kDmMm * kDmMm * kDmMm * kMlPerMm3;
  }

  ibm::ForcingParameters forcing_parameters;
  forcing_parameters.carry_over = fs.forcing_carry_over;
  forcing_parameters.carry_over_factor = fs.forcing_carry_over_factor;
  forcing_parameters.carry_over_exclusion_cells = fs.forcing_carry_over_exclusion_cells;
  forcing_parameters.carry_over_exclusion_rigid = fs.forcing_carry_over_exclusion_plane;  // the plane: the one rigid body
  forcing_parameters.carry_over_exclusion_rigid_cells = fs.forcing_carry_over_exclusion_plane_cells;
  forcing_parameters.carry_over_exclusion_rigid_wall_cells = fs.forcing_carry_over_exclusion_plane_wall_cells;
  forcing_parameters.row_sum_scaling = fs.forcing_row_sum_scaling;
  forcing_parameters.carry_over_increment_share = fs.forcing_carry_over_increment_share;
  forcing_parameters.iterations = fs.forcing_iterations;
  forcing_parameters.rebuild_tolerance_cells = fs.stencil_tolerance_cells;
  forcing_parameters.kernel =
      fs.forcing_kernel == "divergence_free" ? ibm::TransferKernel::divergence_free : ibm::TransferKernel::mls;
  ibm::DirectForcing forcing(slabs, markers, forcing_parameters);
  coupling::FluidModuleOptions fmo;
  fmo.time_scale_ms = kTimeScaleMs;
  fmo.carry_over_reference_cfl = fs.forcing_carry_over_reference_cfl;
  coupling::FluidModule fluid_module(fluid, markers, forcing, fmo);

  // 5. the active tension on the LV and LA walls: nodes within passive_annulus_mm of the anchor
  //    ring (the fibrous annulus) and the vein caps carry none (as in scene electromechanics)
  std::array<std::vector<std::int32_t>, 2> ep_node;  // per chamber: the EP node of each shell node, -1: none
  // per chamber (fsei): the EP node whose potential each shell node shows, the passive annulus included; -1: none
  std::array<std::vector<std::int32_t>, 2> ep_vm_node;
  std::unique_ptr<electro::TissueSolver> tissue;
  std::unique_ptr<coupling::ElectroModule> ep_module;
  std::unique_ptr<ShiftedClock> ep_clock;
  const bool structure_first = fs.coupling_order == "structure_first";
  // fsi in the structure-first order: the prescribed tension's clock is a stage before the shells
  std::unique_ptr<SceneClock> scene_clock;
  if (structure_first && !with_ep)
    scene_clock = std::make_unique<SceneClock>(resume_from ? resumed.scalar("scene/time_ms") : 0.0);
  {
    const geometry::TriMesh& lv_mesh = heart.body(geometry::kLvBody);
    const geometry::TriMesh& la_mesh = heart.body(geometry::kLaBody);
    std::vector<std::array<std::int32_t, 2>> source;
    if (with_ep) {
      LeftHeartEp ep = left_heart_ep(s, lv_mesh, la_mesh);
      source = ep.mesh.source_node;
      tissue = std::make_unique<electro::TissueSolver>(std::move(ep.mesh), std::move(ep.options));
    }
    for (std::size_t c = 0; c < 2; ++c) {
      const geometry::TriMesh& mesh = c == 0 ? lv_mesh : la_mesh;
      auto& map = ep_node[c];
      map.assign(mesh.node_count(), with_ep ? -1 : 0);
      if (with_ep) {
        for (std::size_t k = 0; k < source.size(); ++k)
          if (source[k][0] == static_cast<int>(c)) map[static_cast<std::size_t>(source[k][1])] = static_cast<std::int32_t>(k);
        ep_vm_node[c] = map;
      } else {
        // fsi: every wall node outside the vein caps
        for (std::size_t i = 0; i < mesh.node_count(); ++i)
          if (mesh.region[i] & geometry::kPvOstiumAny) map[i] = -1;
      }
      clear_passive_annulus(mesh, em.passive_annulus_mm, map);
    }
  }
  // fsi: the 0-D activation shapes (LV onset at t = 0, LA at period - av_delay; ours)
  const lumped::ChamberTiming lv_timing = lumped::ChamberTiming::lv(s), la_timing = lumped::ChamberTiming::la(s);
  double scene_time_ms = 0;  // the prescribed tension's clock (the fluid's, at the sync points)
  // The first beat starts at the LV stimulus with the LA at rest: its walls carry no tension
  // before its first stimulus (ours: the stress-free LA is not the end of an atrial contraction;
  // a sudden atrial tension at t = 0 is a jolt the blood cannot follow).
  const double la_first_onset_ms = period_ms - s.av_delay_ms;
  auto set_tension = [&](const std::vector<double>* ep_tension_kpa) {
    for (std::size_t c = 0; c < 2; ++c) {
      if (c == 1 && scene_time_ms < la_first_onset_ms - 1e-9) {
        group.body(kLa).set_active_tension(std::vector<double>(group.body(kLa).node_count(), 0.0));
        continue;
      }
      structure::ShellModel& m = group.body(c == 0 ? kLv : kLa);
      std::vector<double> tau(m.node_count(), 0.0);
      const double prescribed =
          ep_tension_kpa ? 0.0
                         : prescribed_peak_tension_kpa(fs, c == 0 ? Chamber::lv : Chamber::la) *
                               (c == 0 ? lv_timing : la_timing).activation(1e-3 * scene_time_ms);
      for (std::size_t i = 0; i < tau.size(); ++i) {
        const std::int32_t e = ep_node[c][i];
        if (e < 0) continue;
        tau[i] = ep_tension_kpa ? (*ep_tension_kpa)[static_cast<std::size_t>(e)] : prescribed;
      }
      m.set_active_tension(std::move(tau));
    }
  };
  if (with_ep) {
    // EP alone from the LA stimulus (t_EP = 0) to the LV stimulus (t_EP = av_delay): the scene
    // starts at the beginning of systole (ours: the walls feel the tension from then on).
    ep_module = std::make_unique<coupling::ElectroModule>(*tissue);
    const double dt = s.electro.time_step_ms;
    const long n = std::lround(s.av_delay_ms / dt);
    // The scene's t = 0 is the EP clock after the pre-run, exactly: the clock is a sum of n
    // steps, and an offset of n dt would leave the scene's clock 1e-12 ms off the fluid's, so
    // the scheduler's first interval ended on a 1e-12 ms sliver that the fluid stepped (its
    // pressure then blew up: the fsei runs before session 9 stopped at 0.3 ms).
    double ep_offset_ms = 0;
    if (resume_from) {
      tissue->import_state(resumed, "ep/");
      ep_module->import_state(resumed, "ep_module/");
      ep_offset_ms = resumed.scalar("ep_module/offset_ms");
    } else {
      for (long i = 0; i < n; ++i) ep_module->step(dt);
      ep_offset_ms = ep_module->time_ms();
    }
    ep_clock = std::make_unique<ShiftedClock>(*ep_module, ep_offset_ms);
    set_tension(&tissue->active_tension_kpa());
  } else {
    set_tension(nullptr);
  }

  // 6. the stages of one synchronisation interval (Fig. 6)
  const double force_scale_mn = 1e-3 * s.fluid.density_kg_per_m3 * kUmMmPerMs * kUmMmPerMs * kDmMm * kDmMm;  // ρU²d²
  coupling::BodyGroupModule structure_module(group);
  coupling::Transfer tension{"active_tension",
                             [&](std::vector<double>& d) {
                               // [scene time, EP tension per EP node (fsei)]
                               d.assign(1, ep_clock      ? ep_clock->time_ms()
                                           : scene_clock ? scene_clock->time_ms()
                                                         : fluid_module.time_ms());
                               if (with_ep) d.insert(d.end(), tissue->active_tension_kpa().begin(), tissue->active_tension_kpa().end());
                             },
                             [&](const std::vector<double>& d) {
                               scene_time_ms = d[0];
                               if (with_ep) {
                                 const std::vector<double> tau(d.begin() + 1, d.end());
                                 set_tension(&tau);
                               } else {
                                 set_tension(nullptr);
                               }
                             },
                             false};
  std::vector<std::size_t> shell_offset(group.body_count() + 1, 0);
  for (std::size_t b = 0; b < group.body_count(); ++b) shell_offset[b + 1] = shell_offset[b] + group.body(b).node_count();
  // Only the bodies linked to a shell are loaded: the rigid plane's loads are never used, and
  // its markers (16 528 of 98 494 at coarse, two-sided: two probes each) are not probed (ours, for cost).
  std::vector<bool> loaded_bodies(markers.bodies().size(), false);
  for (const Link& l : links) loaded_bodies[static_cast<std::size_t>(l.marker_body)] = true;
  coupling::Transfer loads{"hydrodynamic loads",
                           [&](std::vector<double>& d) {
                             const ibm::MarkerLoads L = fluid_module.loads(loaded_bodies);
                             d.assign(3 * shell_offset.back(), 0.0);
                             for (const Link& l : links) {
                               if (!markers.bodies()[static_cast<std::size_t>(l.marker_body)].active) continue;
                               const std::vector<Vec3> f = l.map.spread(L.nodal_force.at(static_cast<std::size_t>(l.marker_body)),
                                                                        group.body(l.shell).node_count());
                               for (std::size_t n = 0; n < f.size(); ++n)
                                 for (int c = 0; c < 3; ++c) d[3 * (shell_offset[l.shell] + n) + c] += force_scale_mn * f[n][c];
                             }
                           },
                           [&](const std::vector<double>& d) {
                             for (std::size_t b = 0; b < group.body_count(); ++b) {
                               std::vector<Vec3> f(group.body(b).node_count());
                               for (std::size_t n = 0; n < f.size(); ++n) {
                                 const std::size_t i = 3 * (shell_offset[b] + n);
                                 f[n] = Vec3(d[i], d[i + 1], d[i + 2]);
                               }
                               if (b == kAorta && aorta_prestressed && fs.aortic_pressure_ramp_ms > 0)
                                 group.body(b).set_rest_lengths_mm(aorta_rest_lengths_at(fluid_module.time_ms()));
                               if (b == kAorta && aortic_outer_kpa > 0) {
                                 const double ramp = fs.aortic_pressure_ramp_ms > 0
                                                         ? std::min(1.0, fluid_module.time_ms() / fs.aortic_pressure_ramp_ms)
                                                         : 1.0;
                                 add_outer_pressure_loads(heart.body(geometry::kAortaBody), group.body(b).positions_mm(),
                                                          ramp * aortic_outer_kpa, f);
                               }
                               group.body(b).set_external_loads(std::move(f));
                             }
                           },
                           true};
  coupling::Transfer nodes{"structure nodes to the markers",
                           [&](std::vector<double>& d) {
                             d.clear();
                             for (const Link& l : links) {
                               const auto x = l.map.interpolate(group.body(l.shell).positions_mm());
                               const auto v = l.map.interpolate(group.body(l.shell).velocities_mm_per_ms());
                               for (std::size_t n = 0; n < x.size(); ++n)
                                 for (int c = 0; c < 3; ++c) d.push_back(x[n][c] / kDmMm);
                               for (std::size_t n = 0; n < v.size(); ++n)
                                 for (int c = 0; c < 3; ++c) d.push_back(v[n][c] / kUmMmPerMs);
                             }
                           },
                           [&](const std::vector<double>& d) {
                             std::size_t at = 0;
                             for (const Link& l : links) {
                               const std::size_t n = l.map.size();
                               std::vector<Vec3> x(n), v(n);
                               for (std::size_t q = 0; q < n; ++q, at += 3) x[q] = Vec3(d[at], d[at + 1], d[at + 2]);
                               for (std::size_t q = 0; q < n; ++q, at += 3) v[q] = Vec3(d[at], d[at + 1], d[at + 2]);
                               fluid_module.set_body_nodes(l.marker_body, x, v);
                             }
                           },
                           false};
  // A pass: fluid_first (the seed's Fig. 6): [EP,] the fluid, the shells with its loads;
  // structure_first (ours): [EP or the scene's clock,] the shells with the loads last written,
  // the fluid at their new shape. The loads are the relaxed transfer either way.
  std::vector<coupling::Stage> stages;
  if (structure_first)
    stages = {{with_ep ? static_cast<coupling::Module*>(ep_clock.get()) : scene_clock.get(), {tension}},
              {&structure_module, {nodes}},
              {&fluid_module, {loads}}};
  else if (with_ep)
    stages = {{ep_clock.get(), {tension}}, {&fluid_module, {loads}}, {&structure_module, {nodes}}};
  else
    stages = {{&fluid_module, {tension, loads}}, {&structure_module, {nodes}}};
  const auto stage_of = [&](const coupling::Module* m) {
    return static_cast<std::size_t>(std::find_if(stages.begin(), stages.end(), [&](const coupling::Stage& st) {
                                      return st.module == m;
                                    }) - stages.begin());
  };
  const std::size_t fluid_stage = stage_of(&fluid_module), structure_stage = stage_of(&structure_module);
  coupling::SchedulerOptions so;
  so.sync_step_ms = sync_ms;
  // fluid_step: the intervals follow the fluid's stage (ours; EP's tissue keeps its own fixed
  // grid whatever the interval: coupling::ElectroModule)
  if (fs.sync_interval == "fluid_step") so.interval_stage = static_cast<int>(fluid_stage);
  so.interval_stage_steps = fs.fluid_steps_per_interval;
  so.mode = fs.strong_coupling ? coupling::CouplingMode::strong : coupling::CouplingMode::loose;
  so.strong_tolerance = s.coupling.strong_tolerance;
  so.strong_max_iterations = s.coupling.strong_max_iterations;
  so.relaxation = s.coupling.relaxation == "iqn_ils"    ? coupling::Relaxation::iqn_ils
                  : s.coupling.relaxation == "constant" ? coupling::Relaxation::constant
                  : s.coupling.relaxation == "none"     ? coupling::Relaxation::none
                                                        : coupling::Relaxation::aitken;
  so.iqn_reuse_intervals = s.coupling.iqn_reuse_intervals;
  // structure_first: the shells consume the loads before the fluid makes them, so a pass's
  // change of the loads is a fixed-point residual from the first pass on (ours)
  so.first_pass_residual = structure_first;
  so.first_pass_predictor =
      fs.first_pass_predictor == "linear" ? coupling::FirstPassPredictor::linear : coupling::FirstPassPredictor::last;
  // A resumed run: the fluid, the shells and the scheduler where the checkpoint left them, and
  // the markers on the shells' nodes (what the last interval's transfer had set)
  if (resume_from) {
    fluid.restore_checkpoint(*resume_from / "fluid.h5");
    group.import_state(resumed, "structure/");
    forcing.import_state(resumed, "ibm/");  // the carry-over forcing's carried force, if any
    std::vector<double> d;
    nodes.read(d);
    nodes.write(d);
  }
  coupling::Scheduler scheduler(std::move(stages), so);
  if (resume_from) scheduler.import_state(resumed, "scheduler/");

  // 7. probes: LV at 40 % of the long axis below the plane, the aortic root 8 mm above the
  //    aortic orifice, the LA at its nodes' centroid, the outer reference in a box corner, the
  //    descending aorta one outflow radius upstream of the Darcy region (ours; the root's probe
  //    sits in the ejection's jet, whose dynamic pressure it does not see: docs/fsei.md session 16)
  std::vector<Probe> probes;
  {
    const Vec3 lv_c = heart.plane.centre_mm + 0.4 * s.geometry.lv_long_axis_mm * heart.lv_axis_direction;
    const Vec3 ao_c = heart.plane.aortic_centre_mm - 8.0 * heart.lv_axis_direction;
    Vec3 la_c = Vec3::Zero();
    for (const Vec3& p : heart.body(geometry::kLaBody).position_mm) la_c += p;
    la_c /= static_cast<double>(heart.body(geometry::kLaBody).node_count());
    const double r = fs.probe_radius_mm + 1;
    const Vec3 ref(r, r, 0.5 * s.fluid.box_z_mm);
    const Vec3 down = (heart.outflow.end_mm - heart.outflow.start_mm).normalized();
    const Vec3 desc_c = heart.outflow.start_mm - heart.outflow.radius_mm * down;
    probes = {{"lv", lv_c}, {"la", la_c}, {"aortic_root", ao_c}, {"outer", ref}, {"descending_aorta", desc_c}};
  }
  const double mmhg_per_unit = s.fluid.density_kg_per_m3 * units::kSeedVelocity_m_s * units::kSeedVelocity_m_s /
                               units::kPaPerMmHg;
  const double ml_s_per_unit = kUmMmPerMs * 1e3 * kDmMm * kDmMm * kMlPerMm3;  // U d² in ml/s
  // the box's kinetic energy: ρU² (J/m³) × the volume mean of ½|u|² × the box volume (mm³ → m³), in mJ
  const double kinetic_mj_per_unit = 1e3 * s.fluid.density_kg_per_m3 * kUmMmPerMs * kUmMmPerMs *
                                     (g.lx() * g.ly() * g.lz() * kDmMm * kDmMm * kDmMm * 1e-9);

  // 8. run, sampling at outputs.time_series_interval_ms
  RunResult result;
  std::vector<double> t_ms, p_lv, p_la, p_ao, v_lv, v_la, q_ao, q_mi, ke;
  std::vector<double> twist, gls, gcs, u_mitral_tips, u_aortic_tips, wss_cusps;
  std::vector<double> lv_wall_slip, aorta_wall_slip, plane_slip;
  // Series added after a checkpoint's version (not in it) cannot be resumed: they are left out of
  // the result (and of later checkpoints) with a note, never filled in.
  bool wall_slip_series = true;
  // The afterload's flow (ours): through the descending aorta's cross-section where the Darcy
  // region starts (a disk of the outflow's radius normal to z: the procedural heart's descending
  // aorta runs along z; for one that does not, the series is left out with a note), + towards the
  // outlet. With the root pressure it gives the outlet's resistance.
  std::vector<double> q_out;
  // The afterload's pressure (ours): the descending aorta's probe, where the ejection's jet has
  // spread (the root's probe reads low inside it); with q_out, the outlet's resistance.
  std::vector<double> p_desc;
  bool desc_series = true;
  // The kinetic energy of the chambers' blood (the seed's "kinetic energy in the heart"; ke is the
  // whole box's): the cells inside the LV and the LA closed by the valvular plane (chamber_cells.h),
  // for a heart whose long axis runs along z (else left out with a note).
  std::vector<double> ke_heart;
  bool heart_ke_series = std::abs(heart.lv_axis_direction.z()) > 0.99;
  const int lv_side = heart.lv_axis_direction.z() > 0 ? 1 : -1;
  const Vec3 outflow_axis = (heart.outflow.end_mm - heart.outflow.start_mm).normalized();
  bool outlet_series = std::abs(outflow_axis.z()) > 0.99;
  // The immersed boundary's leak seen at the walls (ours): the blood's flux through the LV's and
  // the aorta's markers relative to the walls, −Σ (u(X_b) − V_b)·n_b A_b over each body's active
  // markers, out of the cavity positive (the tiles' normals point into the cavity, the shells'
  // convention). A tight wall has 0; the volume balance's leak (lv_volume_balance_ml) is its
  // integral when the slip at the markers is the whole leak.
  const auto marker_body_named = [&](std::string_view name) {
    for (std::size_t k = 0; k < markers.bodies().size(); ++k)
      if (markers.bodies()[k].name == name) return static_cast<int>(k);
    throw std::logic_error("fsei: no marker body " + std::string(name));
  };
  const int lv_markers = marker_body_named(geometry::kLvBody), aorta_markers = marker_body_named(geometry::kAortaBody);
  // The same through the rigid valvular plane (ours): −Σ (u(X_b) − V_b)·a A_b over its markers,
  // a the LV's axis (base → apex), so positive from the LV side (the LV's cavity) towards the
  // atrium's and the aortic root's side: the plane's share of the LV's leak.
  const int plane_markers = marker_body_named(geometry::kValvularPlaneBody);
  // The wall shear stress (eq 27, extrapolated to the wall: ibm::wall_shear_stress) in Pa: per
  // marker the larger of the two sides' for leaflets; per shell node the area-weighted mean of
  // its tiles' values carried back by the tiling maps (ours). Collective.
  const double pa_per_unit = mmhg_per_unit * units::kPaPerMmHg;
  std::vector<int> link_of_marker_body(markers.bodies().size(), -1);
  for (std::size_t li = 0; li < links.size(); ++li) link_of_marker_body[static_cast<std::size_t>(links[li].marker_body)] = static_cast<int>(li);
  auto marker_wss_pa = [&](const ibm::WallShear& w, std::size_t mk) { return std::max(w.plus[mk], w.minus[mk]) * pa_per_unit; };
  auto node_wss_pa = [&](const ibm::WallShear& w) {
    const ibm::MarkerArrays& ma = markers.markers();
    std::vector<std::vector<Vec3>> sum(links.size());  // per link, per tiled node: (Σ a v, Σ a, 0)
    for (std::size_t li = 0; li < links.size(); ++li)
      sum[li].assign(links[li].map.size(), Vec3::Zero());
    for (std::size_t mk = 0; mk < ma.size(); ++mk) {
      const int li = link_of_marker_body[static_cast<std::size_t>(ma.body[mk])];
      if (li < 0 || !markers.active(mk)) continue;
      const double v = marker_wss_pa(w, mk), a = ma.area[mk];
      for (int c = 0; c < 3; ++c) sum[static_cast<std::size_t>(li)][static_cast<std::size_t>(ma.node[mk][c])] += Vec3(a * v, a, 0);
    }
    std::vector<std::vector<Vec3>> acc(group.body_count());
    for (std::size_t b = 0; b < group.body_count(); ++b) acc[b].assign(group.body(b).node_count(), Vec3::Zero());
    for (std::size_t li = 0; li < links.size(); ++li) {
      const std::vector<Vec3> parent = links[li].map.spread(sum[li], group.body(links[li].shell).node_count());
      for (std::size_t n = 0; n < parent.size(); ++n) acc[links[li].shell][n] += parent[n];
    }
    std::vector<std::vector<double>> out(group.body_count());
    for (std::size_t b = 0; b < acc.size(); ++b) {
      out[b].resize(acc[b].size());
      for (std::size_t n = 0; n < acc[b].size(); ++n) out[b][n] = acc[b][n].y() > 0 ? acc[b][n].x() / acc[b][n].y() : 0.0;
    }
    return out;
  };
  // The wall shear stress per shell node phase-averaged over the beats after the first (the
  // seed's Figs. 16-17), in bins of 0.05 T (ours), written to fsei_wss_phase.h5 at the end.
  constexpr int kWssPhaseBins = 20;
  std::size_t shell_nodes_total = 0;
  for (std::size_t b = 0; b < group.body_count(); ++b) shell_nodes_total += group.body(b).node_count();
  diagnostics::FieldPhaseAverage wss_phase(shell_nodes_total, 1e-3 * period_ms, kWssPhaseBins, 1);
  double wss_phase_from_ms = 0;  // > 0: resumed from a checkpoint without the accumulators
  // Doppler-like sample volumes (ours): disks of half the orifice radius (at most 5 mm) on the
  // valves' axes, at the closed mitral leaflets' tips (their coaptation depth below the plane)
  // and at the closed aortic cusps' tips (their height above it); velocities along the flow
  // (into the LV through the mitral valve, into the aorta through the aortic valve), in m/s.
  const Vec3 mitral_tips = heart.plane.mitral_centre_mm + heart.layout.mitral_coaptation_depth_mm * heart.lv_axis_direction;
  const Vec3 aortic_tips = heart.plane.aortic_centre_mm - heart.layout.cusp_coaptation_height_mm * heart.lv_axis_direction;
  const double mitral_disk_mm = std::min(5.0, 0.5 * heart.plane.mitral_radius_mm);
  const double aortic_disk_mm = std::min(5.0, 0.5 * heart.plane.aortic_radius_mm);
  const geometry::TriMesh& lv_reference = heart.body(geometry::kLvBody);
  const double aortic_orifice_mm2 = std::numbers::pi * heart.plane.aortic_radius_mm * heart.plane.aortic_radius_mm;
  const double mitral_orifice_mm2 = std::numbers::pi * heart.plane.mitral_radius_mm * heart.plane.mitral_radius_mm;
  // the box's kinetic energy (latest sample) as a mean speed of the LV's and LA's blood, m/s
  auto mean_speed_m_s = [&] {
    const double blood_m3 = 1e-6 * (v_lv.back() + v_la.back());
    return blood_m3 > 0 ? std::sqrt(2e-3 * ke.back() / (s.fluid.density_kg_per_m3 * blood_m3)) : 0.0;
  };
  auto sample = [&] {
    const auto p = probe_pressures(fluid, probes, fs.probe_radius_mm);
    t_ms.push_back(fluid_module.time_ms());
    p_lv.push_back((p[0] - p[3]) * mmhg_per_unit);
    p_la.push_back((p[1] - p[3]) * mmhg_per_unit);
    p_ao.push_back((p[2] - p[3]) * mmhg_per_unit);
    if (desc_series) p_desc.push_back((p[4] - p[3]) * mmhg_per_unit);
    v_lv.push_back(group.body(kLv).cavity_volume_mm3() * kMlPerMm3);
    v_la.push_back(group.body(kLa).cavity_volume_mm3() * kMlPerMm3);
    // ejection: the flow through the aortic orifice towards the aorta (-z); filling: through
    // the mitral orifice into the LV (+z)
    q_ao.push_back(-disk_flux(fluid, heart.plane.aortic_centre_mm, heart.plane.aortic_radius_mm) * ml_s_per_unit);
    q_mi.push_back(disk_flux(fluid, heart.plane.mitral_centre_mm, heart.plane.mitral_radius_mm) * ml_s_per_unit);
    if (outlet_series)
      q_out.push_back((outflow_axis.z() > 0 ? 1.0 : -1.0) *
                      disk_flux(fluid, heart.outflow.start_mm, heart.outflow.radius_mm) * ml_s_per_unit);
    {
      const fluid::Velocity& u = fluid.velocity();
      const std::vector<Vec3> ub = forcing.transfer().interpolate(ibm::ConstVelocityView{u.u, u.v, u.w});
      const ibm::MarkerArrays& ma = markers.markers();
      double lv_out = 0, aorta_out = 0, plane_out = 0;
      for (std::size_t mk = 0; mk < ma.size(); ++mk) {
        if (!markers.active(mk)) continue;
        const Vec3 slip = ub[mk] - ma.velocity[mk];
        if (ma.body[mk] == lv_markers) lv_out -= slip.dot(ma.normal[mk]) * ma.area[mk];
        else if (ma.body[mk] == aorta_markers) aorta_out -= slip.dot(ma.normal[mk]) * ma.area[mk];
        else if (ma.body[mk] == plane_markers) plane_out -= slip.dot(heart.lv_axis_direction) * ma.area[mk];
      }
      if (wall_slip_series) {
        lv_wall_slip.push_back(lv_out * ml_s_per_unit);
        aorta_wall_slip.push_back(aorta_out * ml_s_per_unit);
        plane_slip.push_back(plane_out * ml_s_per_unit);
      }
    }
    ke.push_back(fluid.diagnostics().kinetic_energy * kinetic_mj_per_unit);
    if (heart_ke_series) {
      const grid::Slabs& sl = fluid.slabs();
      const grid::Grid& gg = sl.grid();
      const int kb = sl.k_begin(), kc = sl.k_count();
      const std::vector<char> in_heart =
          heart_chambers_cells(group.body(kLv).positions_mm(), group.body(kLv).stress_free_mesh().tri,
                               group.body(kLa).positions_mm(), group.body(kLa).stress_free_mesh().tri, heart.plane.z_mm,
                               lv_side, gg.nx(), gg.ny(), kb, kc, gg.dx() * kDmMm, gg.dy() * kDmMm, gg.dz() * kDmMm);
      const fluid::Velocity& u = fluid.velocity();
      double sum = 0;  // Σ |u|² over the chambers' cells, the fluid's own per-cell reading (its faces at (i, j, k))
      for (int k = 0; k < kc; ++k)
        for (int j = 0; j < gg.ny(); ++j)
          for (int i = 0; i < gg.nx(); ++i) {
            const std::size_t c = (static_cast<std::size_t>(k) * gg.ny() + j) * gg.nx() + i;
            if (in_heart[c]) sum += u.u(i, j, k) * u.u(i, j, k) + u.v(i, j, k) * u.v(i, j, k) + u.w(i, j, k) * u.w(i, j, k);
          }
      MPI_Allreduce(MPI_IN_PLACE, &sum, 1, MPI_DOUBLE, MPI_SUM, sl.comm());
      ke_heart.push_back(0.5 * sum / static_cast<double>(gg.cells()) * kinetic_mj_per_unit);  // as ke: a box mean × the box
    }
    // the LV wall's twist and global strains from the built (end-diastolic, stress-free) shape
    const diagnostics::WallKinematics wk =
        diagnostics::wall_kinematics(lv_reference, group.body(kLv).positions_mm(), heart.lv_axis_direction);
    twist.push_back(wk.twist_deg);
    gls.push_back(wk.longitudinal_strain);
    gcs.push_back(wk.circumferential_strain);
    u_mitral_tips.push_back(disk_mean_w(fluid, mitral_tips, mitral_disk_mm) * kUmMmPerMs);
    u_aortic_tips.push_back(-disk_mean_w(fluid, aortic_tips, aortic_disk_mm) * kUmMmPerMs);
    // the wall shear stress, once per sample (collective: the probes twice over every marker)
    const ibm::WallShear w = fluid_module.wall_shear();
    {  // the aortic cusps' largest wall shear stress (the seed's "> 3 Pa at the tips at peak systole")
      const ibm::MarkerArrays& ma = markers.markers();
      double most = 0;
      for (std::size_t mk = 0; mk < ma.size(); ++mk) {
        const int li = link_of_marker_body[static_cast<std::size_t>(ma.body[mk])];
        if (li < 0 || !markers.active(mk)) continue;
        const std::size_t shell = links[static_cast<std::size_t>(li)].shell;
        if (deformable[shell].rfind("aortic_cusp_", 0) == 0) most = std::max(most, marker_wss_pa(w, mk));
      }
      wss_cusps.push_back(most);
    }
    for (double v : {p_lv.back(), p_la.back(), p_ao.back(), v_lv.back(), v_la.back(), q_ao.back(), q_mi.back(), ke.back(),
                     twist.back(), gls.back(), gcs.back(), u_mitral_tips.back(), u_aortic_tips.back(), wss_cusps.back(),
                     wall_slip_series ? lv_wall_slip.back() : 0.0, wall_slip_series ? aorta_wall_slip.back() : 0.0,
                     wall_slip_series ? plane_slip.back() : 0.0, outlet_series ? q_out.back() : 0.0,
                     desc_series ? p_desc.back() : 0.0, heart_ke_series ? ke_heart.back() : 0.0})
      if (!std::isfinite(v))
        throw InstabilityError("fsei", "diagnostics", 1e-3 * t_ms.back(),
                               "a chamber pressure, volume, flow, wall strain, tip velocity or wall shear stress is not finite");
    // The slow-runaway guard (ours): energy let in by the coupling over tens of ms raises the
    // blood's kinetic energy far above the beat's without a 10-fold jump in one fluid step or a
    // collapse of the step (the fluid's own guards). The box's kinetic energy as a mean speed of
    // the LV's and LA's blood is set against the streams that carry it: the largest mean velocity
    // through a valve's orifice so far (flow / the orifice's area; ml/s per mm² = m/s). In a beat
    // the first stays below the second (docs/fsei.md, session 28: at most 0.80 of it through the
    // ejection at 180 bpm, 0.69 at 70 bpm);
    // above fsei.abort_mean_speed_m_s and more than fsei.abort_mean_speed_orifice_ratio times the
    // orifices' the run stops. Computed from the series, so a resumed run guards as a straight one.
    {
      double orifice_m_s = 0;
      for (double q : q_ao) orifice_m_s = std::max(orifice_m_s, std::abs(q) / aortic_orifice_mm2);
      for (double q : q_mi) orifice_m_s = std::max(orifice_m_s, std::abs(q) / mitral_orifice_mm2);
      const double speed = mean_speed_m_s();
      if (speed > fs.abort_mean_speed_m_s && speed > fs.abort_mean_speed_orifice_ratio * orifice_m_s) {
        std::ostringstream place, what;
        place << "the blood of the LV and LA (" << v_lv.back() + v_la.back() << " ml), fastest cell "
              << fluid.fastest_cell();
        what << "kinetic energy " << ke.back() << " mJ in the box is a mean speed of " << speed
             << " m/s over the chambers' blood, above fsei.abort_mean_speed_m_s = " << fs.abort_mean_speed_m_s
             << " and above fsei.abort_mean_speed_orifice_ratio = " << fs.abort_mean_speed_orifice_ratio
             << " x the largest mean velocity through a valve's orifice so far (" << orifice_m_s
             << " m/s): energy out of proportion to the streams";
        // how fast it came (an abrupt blow-up within a few ms or a slow rise over tens; docs/fsei.md,
        // sessions 28 and 38): the latest earlier sample at half the energy or less
        std::size_t half = ke.size() - 1;
        while (half > 0 && ke[half] > 0.5 * ke.back()) --half;
        if (ke[half] <= 0.5 * ke.back())
          what << "; it doubled in the last " << t_ms.back() - t_ms[half] << " ms (" << ke[half] << " mJ at t = "
               << 1e-3 * t_ms[half] << " s)";
        else
          what << "; it was above half this at every earlier sample (since t = " << 1e-3 * t_ms.front() << " s)";
        throw InstabilityError("fluid", place.str(), 1e-3 * t_ms.back(), what.str());
      }
    }
    std::vector<double> wss_nodes;
    wss_nodes.reserve(shell_nodes_total);
    for (const std::vector<double>& v : node_wss_pa(w)) wss_nodes.insert(wss_nodes.end(), v.begin(), v.end());
    wss_phase.add(1e-3 * t_ms.back(), wss_nodes);
  };
  auto caps_closed = [&](double t) {  // from the LA stimulus to the next LV stimulus
    const double phase = std::fmod(t, period_ms);
    return phase >= period_ms - s.av_delay_ms - 1e-9;
  };
  // The mitral limiter's window (structure.mitral_limiter_end_phase): on over the phases
  // [0, end) of every beat, off after. Engaging it projects every leaflet node back within the
  // limit in the next structure step; how far beyond it a node was is reported (a note), since
  // the projection is a kinematic jump (ours).
  const double limiter_end_ms = s.structure.mitral_limiter_end_phase * period_ms;
  auto mitral_limited = [&](double t) { return mitral_limiter_holds(t, period_ms, s.structure.mitral_limiter_end_phase); };
  bool mitral_limiter_on = s.structure.mitral_limiter;
  double limiter_engage_worst_mm = 0, limiter_engage_worst_t = 0;
  std::string limiter_engage_worst_node;
  int limiter_engagements = 0;
  auto set_mitral_limiter = [&](double t) {
    if (!s.structure.mitral_limiter || mitral_limited(t) == mitral_limiter_on) return;
    mitral_limiter_on = !mitral_limiter_on;
    for (std::string_view name : {geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody}) {
      const auto k = static_cast<std::size_t>(std::find(deformable.begin(), deformable.end(), name) - deformable.begin());
      structure::ShellModel& leaflet = group.body(k);
      if (!mitral_limiter_on) {
        leaflet.clear_displacement_limit();
        continue;
      }
      const std::vector<Vec3>& x = leaflet.positions_mm();
      const std::vector<Vec3>& x0 = heart.body(name).position_mm;  // the built, closed valve
      for (std::size_t i = 0; i < x.size(); ++i) {
        const double beyond = (x0[i] - x[i]).z() - s.structure.mitral_limit_mm;  // towards the LA, -z
        if (beyond > limiter_engage_worst_mm)
          limiter_engage_worst_mm = beyond, limiter_engage_worst_t = t,
          limiter_engage_worst_node = std::string(name) + "' node " + std::to_string(i);
      }
      leaflet.set_displacement_limit(-Vec3::UnitZ(), s.structure.mitral_limit_mm, x0);
    }
    if (mitral_limiter_on) ++limiter_engagements;
  };
  auto set_caps = [&](double t) {
    for (const Link& l : links)
      if (l.cap && markers.bodies()[static_cast<std::size_t>(l.marker_body)].active != caps_closed(t)) {
        markers.set_active(l.marker_body, caps_closed(t));
        forcing.markers_moved();
      }
  };
  // The scene's own state in a checkpoint: the series sampled so far and the field frames.
  const std::vector<std::pair<std::string, std::vector<double>*>> series_state{
      {"t_ms", &t_ms},       {"p_lv", &p_lv},   {"p_la", &p_la},   {"p_ao", &p_ao},
      {"v_lv", &v_lv},       {"v_la", &v_la},   {"q_ao", &q_ao},   {"q_mi", &q_mi},
      {"ke", &ke},           {"twist", &twist}, {"gls", &gls},     {"gcs", &gcs},
      {"u_mitral_tips", &u_mitral_tips},        {"u_aortic_tips", &u_aortic_tips},
      {"wss_cusps", &wss_cusps},               {"lv_wall_slip", &lv_wall_slip},
      {"aorta_wall_slip", &aorta_wall_slip},   {"plane_slip", &plane_slip},
      {"q_out", &q_out},                       {"p_desc", &p_desc},
      {"ke_heart", &ke_heart}};
  // The series sampled so far, named with their units: the result's at the end, and what
  // RunControl::on_checkpoint gets at each checkpoint (a running job's series).
  auto named_series = [&] {
    std::vector<Series> out;
    auto add = [&](const std::string& name, const std::string& unit, const std::vector<double>& v) {
      out.push_back({name, unit, v});
    };
    std::vector<double> t_s(t_ms.size());
    for (std::size_t i = 0; i < t_ms.size(); ++i) t_s[i] = 1e-3 * t_ms[i];
    add("time_s", "s", t_s);
    add("lv_pressure_mmhg", "mmHg", p_lv);
    add("la_pressure_mmhg", "mmHg", p_la);
    add("aortic_root_pressure_mmhg", "mmHg", p_ao);
    add("lv_volume_ml", "ml", v_lv);
    add("la_volume_ml", "ml", v_la);
    add("aortic_flow_ml_s", "ml/s", q_ao);
    add("mitral_flow_ml_s", "ml/s", q_mi);
    add("kinetic_energy_mj", "mJ", ke);
    if (heart_ke_series) add("heart_kinetic_energy_mj", "mJ", ke_heart);
    add("lv_twist_deg", "deg", twist);
    add("lv_longitudinal_strain", "", gls);
    add("lv_circumferential_strain", "", gcs);
    add("mitral_tip_velocity_m_s", "m/s", u_mitral_tips);
    add("aortic_tip_velocity_m_s", "m/s", u_aortic_tips);
    if (wall_slip_series) {
      add("lv_wall_slip_flux_ml_s", "ml/s", lv_wall_slip);
      add("aorta_wall_slip_flux_ml_s", "ml/s", aorta_wall_slip);
      add("valvular_plane_slip_flux_ml_s", "ml/s", plane_slip);
    }
    if (outlet_series) add("aortic_outlet_flow_ml_s", "ml/s", q_out);
    if (desc_series) add("descending_aorta_pressure_mmhg", "mmHg", p_desc);
    add("aortic_cusps_wss_max_pa", "Pa", wss_cusps);
    return out;
  };
  double t = 0;
  set_caps(0);
  set_mitral_limiter(0);
  if (resume_from) {
    t = resumed.scalar("scene/time_ms");
    const long samples = static_cast<long>(resumed.get("series/t_ms").size());
    wall_slip_series = resumed.has("series/lv_wall_slip") && resumed.has("series/plane_slip");
    outlet_series = outlet_series && resumed.has("series/q_out");
    desc_series = resumed.has("series/p_desc");
    heart_ke_series = heart_ke_series && resumed.has("series/ke_heart");
    for (auto& [name, v] : series_state)
      if ((wall_slip_series || (v != &lv_wall_slip && v != &aorta_wall_slip && v != &plane_slip)) &&
          (outlet_series || v != &q_out) && (desc_series || v != &p_desc) && (heart_ke_series || v != &ke_heart))
        *v = resumed.get("series/" + name, samples);
    // (a checkpoint of an earlier version has no phase-average accumulators: they start here)
    wss_phase_from_ms = resumed.has("scene/wss_phase/beat") ? 0.0 : t;
    if (wss_phase_from_ms == 0) wss_phase.import_state(resumed, "scene/wss_phase/");
    set_caps(t);
    set_mitral_limiter(t);
  } else {
    sample();
  }
  // Field frames into the caller's output directory: every fsei.field_interval_ms from t = 0
  // and/or at the phases outputs.field_phases (t/T) of every beat.
  const std::vector<double>& field_phases = s.outputs.field_phases;
  const bool fields_wanted = fs.field_interval_ms > 0 || !field_phases.empty();
  auto next_phase_frame = [&](double after_ms) {  // the first (k + phase) T later than after_ms
    double best = 1e300;
    const double k0 = std::floor(after_ms / period_ms);
    for (double k : {k0, k0 + 1})
      for (double phase : field_phases)
        if ((k + phase) * period_ms > after_ms + 1e-9) best = std::min(best, (k + phase) * period_ms);
    return best;
  };
  std::unique_ptr<FseiFieldWriter> fields;
  long field_frames_done = 0;  // the next interval frame is at field_frames_done × fsei.field_interval_ms
  std::vector<double> resumed_frames_ms;
  if (resume_from && resumed.has("scene/field_times_ms")) resumed_frames_ms = resumed.get("scene/field_times_ms");
  if (fields_wanted && !control.output_directory().empty()) {
    fluid::FluidSolver::FieldSelection units;
    units.velocity_scale = kUmMmPerMs;                 // U (mm/ms = m/s)
    units.pressure_scale = mmhg_per_unit;              // ρU² in mmHg
    units.vorticity_scale = 1e3 * kUmMmPerMs / kDmMm;  // U/d in 1/s
    units.gzip_level = 4;                              // shuffle + gzip (ours: level 4)
    std::vector<std::string> names(deformable.begin(), deformable.end());
    std::function<std::vector<double>(std::size_t)> node_vm_mv;  // fsei: the EP's potential at the LV's and LA's nodes
    if (with_ep)
      node_vm_mv = [&](std::size_t b) {
        if (b != kLv && b != kLa) throw std::logic_error("fsei fields: body " + std::to_string(b) + " has no potential");
        const std::vector<std::int32_t>& map = ep_vm_node[b == kLv ? 0 : 1];
        std::vector<double> vm(map.size(), std::numeric_limits<double>::quiet_NaN());
        for (std::size_t i = 0; i < map.size(); ++i)
          if (map[i] >= 0) vm[i] = tissue->vm_mv()[static_cast<std::size_t>(map[i])];
        return vm;
      };
    fields = std::make_unique<FseiFieldWriter>(control.output_directory(), g, kDmMm,
                                               heart.body(geometry::kValvularPlaneBody), group, names, units,
                                               std::move(node_vm_mv), resume_from ? &resumed_frames_ms : nullptr);
    const bool phase_zero = std::find(field_phases.begin(), field_phases.end(), 0.0) != field_phases.end();
    if (!resume_from && (fs.field_interval_ms > 0 || phase_zero))
      fields->frame(0.0, fluid, group, node_wss_pa(fluid_module.wall_shear()));
    // resumed: the next frame after the checkpoint's time, whether the frames continue in the
    // same directory or start anew (a new directory, another interval)
    if (fs.field_interval_ms > 0)
      field_frames_done = resume_from ? static_cast<long>(std::floor(t / fs.field_interval_ms + 1e-9)) + 1 : 1;
  }
  // Checkpoints every fsei.checkpoint_interval_ms of simulated time (at a sample), and when the
  // run is cancelled (a worker that stops hands the job back at that point). Collective.
  const double checkpoint_ms = checkpoint_root.empty() ? 0.0 : fs.checkpoint_interval_ms;
  double next_checkpoint_ms = checkpoint_ms > 0 ? (std::floor(t / checkpoint_ms + 1e-9) + 1) * checkpoint_ms : 1e300;
  long checkpoints_written = 0;
  auto write_checkpoint = [&] {
    CheckpointDirectory dir(checkpoint_root);
    const std::filesystem::path next_dir = dir.begin();
    fluid.write_checkpoint(next_dir / "fluid.h5");
    int ok = 1;
    std::string error;
    if (is_rank_zero()) {
      try {
        StateArchive a;
        a.put_scalar("scene/time_ms", t);
        group.export_state(a, "structure/");
        forcing.export_state(a, "ibm/");
        if (with_ep) {
          tissue->export_state(a, "ep/");
          ep_module->export_state(a, "ep_module/");
          a.put_scalar("ep_module/offset_ms", ep_clock->offset_ms());
        }
        scheduler.export_state(a, "scheduler/");
        for (const auto& [name, v] : series_state)
          if (v->size() == t_ms.size()) a.put("series/" + name, *v);
        wss_phase.export_state(a, "scene/wss_phase/");
        if (fields) a.put("scene/field_times_ms", fields->frame_times_ms());
        write_state_file(next_dir / "state.h5", a, fingerprint);
      } catch (const std::exception& e) {
        ok = 0;
        error = e.what();
      }
    }
    MPI_Bcast(&ok, 1, MPI_INT, 0, MPI_COMM_WORLD);
    if (!ok) throw std::runtime_error("fsei checkpoint at t = " + std::to_string(t) + " ms: " + error);
    dir.publish();
    ++checkpoints_written;
    RunResult so_far;
    so_far.series = named_series();
    control.on_checkpoint(so_far);
  };
  const double dt_sample = s.outputs.time_series_interval_ms;
  try {
  while (t < end_ms - 1e-9) {
    // the next sample, clipped at a cap switch (the LA stimulus, the LV stimulus) and at a field
    // frame (which is not a sample)
    double next = std::min(end_ms, (std::floor(t / dt_sample + 1e-9) + 1) * dt_sample);
    const double beat0 = std::floor(t / period_ms + 1e-9) * period_ms;
    for (double sw : {beat0 + period_ms - s.av_delay_ms, beat0 + period_ms, beat0 + limiter_end_ms})
      if (sw > t + 1e-9 && sw < next) next = sw;
    const double next_interval_frame =
        fields && fs.field_interval_ms > 0 ? static_cast<double>(field_frames_done) * fs.field_interval_ms : 1e300;
    const double next_field = fields ? std::min(next_interval_frame, next_phase_frame(t)) : 1e300;
    const bool field_only = next_field < next - 1e-9;
    if (field_only) next = next_field;
    try {
      scheduler.advance_to(next);
    } catch (const ibm::WallProximityError& e) {
      // a body came within a cell of the box's z wall: a diagnosis with the nearest shell node
      const Vec3 at_mm = e.point() * kDmMm;
      std::size_t best_body = 0, best_node = 0;
      double best = 1e300;
      for (std::size_t b = 0; b < group.body_count(); ++b) {
        const std::vector<Vec3>& x = group.body(b).positions_mm();
        for (std::size_t n = 0; n < x.size(); ++n)
          if ((x[n] - at_mm).squaredNorm() < best) best = (x[n] - at_mm).squaredNorm(), best_body = b, best_node = n;
      }
      std::ostringstream place, what;
      place.precision(4);
      place << "body '" << group.body(best_body).name() << "' node " << best_node << " (a marker or load probe at ("
            << at_mm.x() << ", " << at_mm.y() << ", " << at_mm.z() << ") mm)";
      what << "a body moved within a cell of the box's z wall (z in [0, " << s.fluid.box_z_mm
           << "] mm): the immersed boundary's support would leave the fluid";
      throw InstabilityError("immersed boundary", place.str(), 1e-3 * scheduler.time_ms(), what.str());
    }
    t = next;
    set_caps(t);
    set_mitral_limiter(t);
    if (fields && std::abs(t - next_field) < 1e-9) {
      fields->frame(t, fluid, group, node_wss_pa(fluid_module.wall_shear()));
      if (std::abs(t - next_interval_frame) < 1e-9) ++field_frames_done;
    }
    if (field_only) continue;
    sample();
    ProgressReport rep;
    rep.simulated_time_s = 1e-3 * t;
    rep.beat = 1 + static_cast<int>(t / period_ms);
    rep.beats_total = static_cast<int>(std::ceil(end_ms / period_ms - 1e-9));
    rep.fraction = t / end_ms;
    {
      std::ostringstream m;  // the latest sample, so a run that stops later leaves its trend
      m.precision(7);
      m << s.scene << " t_ms " << t << " p_lv_mmhg " << p_lv.back() << " p_la_mmhg " << p_la.back() << " p_ao_mmhg "
        << p_ao.back() << " v_lv_ml " << v_lv.back() << " v_la_ml " << v_la.back() << " q_ao_ml_s " << q_ao.back()
        << " q_mi_ml_s " << q_mi.back() << " ke_mj " << ke.back() << " mean_speed_m_s " << mean_speed_m_s();
      if (wall_slip_series)
        m << " lv_slip_ml_s " << lv_wall_slip.back() << " aorta_slip_ml_s " << aorta_wall_slip.back() << " plane_slip_ml_s "
          << plane_slip.back();
      if (outlet_series) m << " q_out_ml_s " << q_out.back();
      if (desc_series) m << " p_desc_mmhg " << p_desc.back();
      {  // what sets the fluid's step (CFL bound: the three largest speeds, each over its own faces)
        const fluid::FluidParameters& fp = fluid.parameters();
        const double m_s = 1e-3 * fp.length_scale_mm / fp.time_scale_s;
        const std::array<double, 3> u = fluid.max_velocity();
        m << " fluid_dt_ms " << 1e3 * fp.time_scale_s * fluid.last_dt() << " max_uvw_m_s " << u[0] * m_s << " "
          << u[1] * m_s << " " << u[2] * m_s << " fastest " << fluid.fastest_cell();
        // and the fastest node of the shells (mm/ms = m/s): a body moving fast drags its blood
        double v_max = 0;
        std::string v_body = "-";
        for (std::size_t b = 0; b < group.body_count(); ++b)
          for (const Vec3& v : group.body(b).velocities_mm_per_ms())
            if (v.norm() > v_max) v_max = v.norm(), v_body = group.body(b).name();
        m << " fastest_node_m_s " << v_max << " in " << v_body;
        // and the largest carried-over force (the forcing's integral state, m/s²: what winds up
        // where the slip cannot be removed), its body, place and whether it carries (ours,
        // session 43: docs/fsei.md's analysis of the 1-h exclusion at small steps)
        const std::vector<Vec3>& carried = forcing.carried_force();
        if (!carried.empty()) {
          std::size_t b_max = 0;
          double f_max = -1;
          for (std::size_t b = 0; b < carried.size(); ++b)
            if (carried[b].squaredNorm() > f_max) f_max = carried[b].squaredNorm(), b_max = b;
          const ibm::MarkerArrays& ma = markers.markers();
          const Vec3 x_mm = ma.position[b_max] * fp.length_scale_mm;
          m << " carried_force_max_m_s2 " << std::sqrt(f_max) * m_s / fp.time_scale_s << " in "
            << markers.bodies()[static_cast<std::size_t>(ma.body[b_max])].name << " at (" << x_mm.x() << ", "
            << x_mm.y() << ", " << x_mm.z() << ") mm " << (forcing.carries_over(b_max) ? "carrying" : "excluded");
        }
      }
      if (fs.strong_coupling) {  // how the iterations fare so far (a run that stops reports no metrics)
        const coupling::SchedulerStats& cs = scheduler.stats();
        m << " passes " << cs.passes << " unconverged " << cs.unconverged_intervals << " of " << cs.intervals
          << " intervals, largest final residual " << cs.max_final_residual;
      }
      rep.message = m.str();
    }
    control.on_progress(rep);
    if (control.cancel_requested()) {
      if (checkpoint_ms > 0) write_checkpoint();
      throw Cancelled();
    }
    if (t >= next_checkpoint_ms - 1e-9 && t < end_ms - 1e-9) {
      write_checkpoint();
      next_checkpoint_ms = (std::floor(t / checkpoint_ms + 1e-9) + 1) * checkpoint_ms;
    }
  }
  } catch (const InstabilityError&) {
    // the bodies as they were when the run stopped: the diagnosis in pictures (rank 0 alone,
    // no communication; the stop itself is reported by rethrowing)
    if (fields) {
      try {
        fields->bodies_frame(group.body(0).time_ms(), group, "unstable");
      } catch (const std::exception&) {
        // the frame is a help; what is reported is the instability below
      }
    }
    throw;
  }

  // 9. metrics and series
  auto& M = result.metrics;
  auto max_of = [](const std::vector<double>& v) { return *std::max_element(v.begin(), v.end()); };
  auto min_of = [](const std::vector<double>& v) { return *std::min_element(v.begin(), v.end()); };
  M["lv_pressure_start_mmhg"] = p_lv.front();
  M["lv_pressure_max_mmhg"] = max_of(p_lv);
  M["la_pressure_max_mmhg"] = max_of(p_la);
  M["aortic_root_pressure_max_mmhg"] = max_of(p_ao);
  M["lv_volume_start_ml"] = v_lv.front();
  M["lv_volume_min_ml"] = min_of(v_lv);
  M["lv_volume_end_ml"] = v_lv.back();
  M["la_volume_start_ml"] = v_la.front();
  M["la_volume_end_ml"] = v_la.back();
  M["aortic_flow_max_ml_s"] = max_of(q_ao);
  M["aortic_flow_min_ml_s"] = min_of(q_ao);
  M["mitral_flow_max_ml_s"] = max_of(q_mi);
  M["mitral_flow_min_ml_s"] = min_of(q_mi);
  // The volume a flow series (ml/s) carried over the run: the trapezoidal ∫ over the samples.
  auto volume_ml = [&](const std::vector<double>& q_ml_s) {
    double ml = 0;
    for (std::size_t i = 1; i < t_ms.size(); ++i) ml += 0.5 * 1e-3 * (t_ms[i] - t_ms[i - 1]) * (q_ml_s[i] + q_ml_s[i - 1]);
    return ml;
  };
  // What the LV lost beyond what left through its orifices: the leak of the immersed boundary
  // across the wall and the closed leaflets (ours).
  M["lv_volume_balance_ml"] = (v_lv.back() - v_lv.front()) + volume_ml(q_ao) - volume_ml(q_mi);
  // The same leak seen at the LV's markers and at the plane's (out of the LV positive): together
  // −lv_volume_balance_ml when the slip at the markers is the whole leak.
  if (wall_slip_series) {
    M["lv_wall_slip_volume_ml"] = volume_ml(lv_wall_slip);
    M["valvular_plane_slip_volume_ml"] = volume_ml(plane_slip);
  } else {
    result.notes.push_back("resumed from a checkpoint without the wall-slip series: lv_wall_slip_flux_ml_s, "
                           "aorta_wall_slip_flux_ml_s, valvular_plane_slip_flux_ml_s, lv_wall_slip_volume_ml and "
                           "valvular_plane_slip_volume_ml are not reported");
  }
  if (slabs.size() > 1) {
    std::ostringstream m;
    m << "the fluid's " << g.nz() << " z planes over " << slabs.size() << " ranks (fsei.slab_split = " << fs.slab_split
      << "):";
    for (int r = 0; r < slabs.size(); ++r) {
      const grid::Range z = slabs.z_range(r);
      long in = 0;
      for (double mz : marker_z) {
        const int k = plane_of(g, mz);
        in += k >= z.begin && k < z.begin + z.count;
      }
      m << (r ? "," : "") << " rank " << r << " planes [" << z.begin << ", " << z.begin + z.count << ") with " << in
        << " of the " << marker_z.size() << " markers at rest";
    }
    result.notes.push_back(m.str());
  }
  if (!outlet_series)
    result.notes.push_back(std::abs(outflow_axis.z()) > 0.99
                               ? "resumed from a checkpoint without the outlet's flow: aortic_outlet_flow_ml_s is not reported"
                               : "the descending aorta's outlet is not along z: aortic_outlet_flow_ml_s is not reported");
  if (s.structure.mitral_limiter && s.structure.mitral_limiter_end_phase < 1) {
    std::ostringstream m;
    m << "the mitral limiter held over t/T in [0, " << s.structure.mitral_limiter_end_phase << ") of every beat; engaged "
      << limiter_engagements << " time(s) at a beat's start in this run";
    if (limiter_engage_worst_mm > 0)
      m << ", the farthest node beyond its limit at an engagement: body '" << limiter_engage_worst_node << " by "
        << limiter_engage_worst_mm << " mm at t = " << limiter_engage_worst_t << " ms (projected back in one step)";
    result.notes.push_back(m.str());
  }
  if (!desc_series)
    result.notes.push_back("resumed from a checkpoint without the descending aorta's pressure: "
                           "descending_aorta_pressure_mmhg is not reported");
  if (!heart_ke_series)
    result.notes.push_back(std::abs(heart.lv_axis_direction.z()) > 0.99
                               ? "resumed from a checkpoint without the chambers' kinetic energy: "
                                 "heart_kinetic_energy_mj is not reported"
                               : "the LV's long axis does not run along z: heart_kinetic_energy_mj is not reported");
  M["kinetic_energy_max_mj"] = max_of(ke);
  if (heart_ke_series) M["heart_kinetic_energy_max_mj"] = max_of(ke_heart);
  auto largest = [](const std::vector<double>& v) {  // the sample of largest magnitude, signed
    double best = 0;
    for (double x : v) if (std::abs(x) > std::abs(best)) best = x;
    return best;
  };
  M["lv_twist_peak_deg"] = largest(twist);
  M["lv_longitudinal_strain_min"] = min_of(gls);
  M["lv_circumferential_strain_min"] = min_of(gcs);
  M["mitral_tip_velocity_max_m_s"] = max_of(u_mitral_tips);
  M["aortic_tip_velocity_max_m_s"] = max_of(u_aortic_tips);
  M["aortic_cusps_wss_max_pa"] = max_of(wss_cusps);
  M["simulated_time_ms"] = t;
  M["resumed_from_ms"] = resume_from ? resumed.scalar("scene/time_ms") : 0.0;  // 0: a run from t = 0
  const auto& st = scheduler.stats();
  M["fluid_steps"] = static_cast<double>(st.modules[fluid_stage].steps);
  M["structure_substeps"] = static_cast<double>(st.modules[structure_stage].steps);
  // the tissue's own steps from its t = 0 (the LA stimulus: the av delay's pre-run included, and
  // those before a checkpoint); the scheduler's calls of the EP stage are more (sub-cycles of
  // each pass, replays after a restore)
  M["ep_steps"] = with_ep ? static_cast<double>(std::lround(tissue->time_ms() / s.electro.time_step_ms)) : 0.0;
  M["coupling_intervals"] = static_cast<double>(st.intervals);
  // strong coupling: passes in all (= intervals when loose), intervals that ended at the pass
  // limit, and the largest relative change of the transferred data at an interval's end
  M["coupling_passes"] = static_cast<double>(st.passes);
  M["coupling_unconverged_intervals"] = static_cast<double>(st.unconverged_intervals);
  M["coupling_max_final_residual"] = st.max_final_residual;
  double over = 0;
  for (const auto& m : st.modules) over = std::max(over, m.max_step_over_limit);
  M["max_step_over_limit"] = over;
  M["grid_cells"] = static_cast<double>(g.cells());
  M["markers"] = static_cast<double>(markers.size());
  M["shell_nodes"] = static_cast<double>(shell_offset.back());
  M["field_frames"] = fields ? fields->frames() : 0;
  M["ep_wall_s"] = with_ep ? st.modules[0].wall_time_s : 0.0;
  M["fluid_wall_s"] = st.modules[fluid_stage].wall_time_s;
  M["structure_wall_s"] = st.modules[structure_stage].wall_time_s;
  result.series = named_series();
  {
    std::vector<std::map<std::string, double>> beats = fsei_beat_metrics(result.series, period_ms, s.fluid.density_kg_per_m3, s.scene);
    M["beats_completed"] = static_cast<double>(beats.size());
    M["heart_rate_bpm"] = 60000.0 / period_ms;
    // the last whole beat's metrics also at the top (metrics.json, systole-plot-beat); present
    // only when a beat completed
    if (!beats.empty())
      for (const auto& [key, value] : beats.back())
        if (!M.count(key)) M[key] = value;
    if (s.outputs.metrics) result.beats = std::move(beats);
    // Phase averages over the whole beats after the first (the seed's statistics), in bins of
    // 0.01 T (ours), or of two sample intervals when the sampling is coarser (so that every bin
    // holds a sample).
    const int bins = std::min(100, static_cast<int>(std::floor(period_ms / (2 * dt_sample))));
    if (M["beats_completed"] >= 2 && bins >= 1) {
      try {
        result.phase_averaged = diagnostics::phase_averaged_series(result.series, 1e-3 * period_ms, bins, 1);
      } catch (const std::invalid_argument& e) {  // the run's results stand without them
        result.notes.push_back(std::string("phase averages not computed: ") + e.what());
      }
    }
  }
  result.notes.push_back("scene " + s.scene + " at resolution " + fs.resolution + " (" + std::to_string(pts.nx) + "x" +
                         std::to_string(pts.ny) + "x" + std::to_string(pts.nz) + " points), " +
                         std::to_string(markers.size()) + " markers; chamber pressures relative to the outer-fluid probe");
  {
    std::ostringstream m;
    m << "markers per body (tiling level m, markers):";
    for (const auto& b : markers.bodies()) m << " " << b.name << " m=" << b.tiling_level << " " << b.marker_count << ";";
    result.notes.push_back(m.str());
  }
  const ibm::DirectForcing::ExclusionRadii rings = forcing.carry_over_exclusion_radii();
  if (forcing_parameters.carry_over && rings.rigid_wall_cells > 0) {
    std::ostringstream m;
    m << "carry-over forcing: " << forcing.carry_over_excluded() << " of " << markers.size() << " markers (those within "
      << rings.pair_cells << " h of another body's, " << rings.rigid_cells << " h of the plane's (walls: "
      << rings.rigid_wall_cells << " h), at the end) carry nothing over";
    result.notes.push_back(m.str());
  }
  if (wss_phase.beats(0) > 0 && !control.output_directory().empty()) {
    if (is_rank_zero()) {
      std::vector<std::string> names(deformable.begin(), deformable.end());
      write_wss_phase_average(control.output_directory(), group, names, wss_phase);
    }
    result.notes.push_back("wall shear stress per shell node phase-averaged over " + std::to_string(wss_phase.beats(0)) +
                           " beats after the first (mean and rms, " + std::to_string(kWssPhaseBins) +
                           " phase bins" +
                           (wss_phase_from_ms > 0 ? ", sampled from the resume at " + std::to_string(wss_phase_from_ms) + " ms" : std::string()) +
                           "): fsei_wss_phase.xmf");
  }
  if (fields) {
    std::ostringstream m;
    m << fields->frames() << " field frames";
    if (fs.field_interval_ms > 0) m << " every " << fs.field_interval_ms << " ms";
    if (!field_phases.empty()) {
      m << (fs.field_interval_ms > 0 ? " and" : "") << " at t/T =";
      for (double phase : field_phases) m << " " << phase;
      m << " of every beat";
    }
    m << ": fsei_fields.xmf (fluid fsei_fluid_<k>.h5, bodies fsei_bodies.h5)";
    if (!s.outputs.fields.empty()) m << "; outputs.fields does not select among them: every frame has all the fields";
    result.notes.push_back(m.str());
  } else if (fields_wanted) {
    result.notes.push_back(
        "fields were requested (fsei.field_interval_ms, outputs.field_phases) but the caller gave no output directory: none "
        "written");
  }
  if (fs.aortic_pressure_mmhg > 0) {
    std::ostringstream m;
    m << "aorta pre-tension: ground pressure " << fs.aortic_pressure_mmhg << " mmHg (";
    if (aorta_prestress)
      m << (wall_share < 1 ? std::to_string(wall_share) + " of it by " : std::string()) << "a pre-stress of the wall: springs shortened by " << 100 * aorta_prestress->mean_strain << " % on average, "
        << 100 * aorta_prestress->max_strain << " % at most (spring " << aorta_prestress->max_strain_spring << "), "
        << aorta_prestress->compressed_springs << " pre-compressed (down to " << 100 * aorta_prestress->min_strain
        << " %), equilibrium residual " << aorta_prestress->residual_relative
        << " of the load; " << (wall_share < 1 ? "the rest by an outer load on the wall outside the Darcy region; " : "");
    else
      m << "outer load on the wall outside the Darcy region; ";
    if (fs.aortic_pressure_ramp_ms > 0)
      m << "ramped over " << fs.aortic_pressure_ramp_ms << " ms from the blood at rest)";
    else
      m << "the blood inside the aorta, " << aorta_initial_ml << " ml, started at it)";
    result.notes.push_back(m.str());
  }
  if (resume_from) {
    std::ostringstream m;
    m << "resumed from the checkpoint at t = " << resumed.scalar("scene/time_ms") << " ms in " << resume_from->string();
    if (fields && !fields->earlier_frames_present())
      m << "; the field frames written before it are not in this output directory (left out of fsei_fields.xmf)";
    result.notes.push_back(m.str());
  }
  if (checkpoints_written > 0)
    result.notes.push_back(std::to_string(checkpoints_written) + " checkpoints written every " +
                           std::to_string(checkpoint_ms) + " ms into " + checkpoint_root.string());
  if (!is_rank_zero()) result.notes.clear();
  return result;
}

}  // namespace systole::scene
