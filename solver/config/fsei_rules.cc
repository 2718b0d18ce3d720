#include "solver/config/fsei_rules.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/core/units.h"

namespace systole::config {
namespace {

// The scene's length scale d_m (MODEL.md §3): the grid's spacing is computed in it, as the scene does.
constexpr double kDmMm = 1000 * units::kSeedLength_m;

// The aorta's ground pressure: the wall's share of it is a pre-stress's (fsei.aorta.pretension).
void check_aortic_pretension(const Fsei& fs, std::vector<std::string>& errors) {
  if (fs.aorta.prestress_fraction == 1 || fs.aorta.pretension == "prestress") return;
  std::ostringstream m;
  m << "fsei.aorta.prestress_fraction = " << fs.aorta.prestress_fraction
    << " is the share of the pre-stress: it needs fsei.aorta.pretension = \"prestress\" (got \"" << fs.aorta.pretension
    << "\"); with \"outer_load\" leave it at 1";
  errors.push_back(m.str());
}

// The coupling's stages: the shells-first order, its first-pass guess, intervals of fluid steps.
void check_coupling(const Fsei& fs, std::vector<std::string>& errors) {
  // Loose coupling in the shells-first order would hand the shells the loads of the last pass
  // without keeping them in a checkpoint; the order is for strong coupling's one-pass intervals.
  if (fs.coupling_order == "structure_first" && !fs.strong_coupling)
    errors.push_back("fsei.coupling_order = \"structure_first\" needs fsei.strong_coupling = true (its point is strong "
                     "coupling's first-pass check; got false); with loose coupling use \"fluid_first\"");
  if (fs.first_pass_predictor == "linear" && fs.coupling_order != "structure_first")
    errors.push_back("fsei.first_pass_predictor = \"linear\" needs fsei.coupling_order = \"structure_first\" (it guesses "
                     "the loads the shells take before the fluid makes them); got \"" + fs.coupling_order +
                     "\"; with \"fluid_first\" use \"last\"");
  if (fs.sync_interval == "fixed" && fs.fluid_steps_per_interval != 1)
    errors.push_back("fsei.fluid_steps_per_interval = " + std::to_string(fs.fluid_steps_per_interval) +
                     " needs fsei.sync_interval = \"fluid_step\"; with fixed intervals (of fsei.sync_step_ms) leave it at 1");
}

void check_mitral_limiter(const Structure& st, std::vector<std::string>& errors) {
  if (st.mitral_limiter_end_phase == 1 || st.mitral_limiter) return;
  std::ostringstream m;
  m << "structure.mitral_limiter_end_phase = " << st.mitral_limiter_end_phase
    << " is the mitral limiter's window: it needs structure.mitral_limiter = true (got false); without the limiter "
       "leave it at 1";
  errors.push_back(m.str());
}

// Scene fsei: the EP runs on the chambers' walls, in whole steps per synchronisation step.
void check_electrophysiology(const Scenario& s, std::vector<std::string>& errors) {
  const double ratio = s.fsei.sync_step_ms / s.electro.time_step_ms;
  if (ratio < 1 - 1e-9 || std::abs(ratio - std::round(ratio)) > 1e-6 * ratio) {
    std::ostringstream m;
    m << "fsei.sync_step_ms = " << s.fsei.sync_step_ms << " ms must be a whole multiple of electro.time_step_ms = "
      << s.electro.time_step_ms << " ms (scene fsei)";
    errors.push_back(m.str());
  }
  if (s.electro.mesh != "left_heart")
    errors.push_back("electro.mesh = \"" + s.electro.mesh +
                     "\" is not allowed in scene fsei; allowed: left_heart (the EP runs on the heart's walls)");
}

// The grid's spacing per axis (mm), as grid::Grid makes it: the box over points - 1 cells.
std::array<double, 3> spacing_mm(const Scenario& s, const GridPoints& pts) {
  return {s.fluid.box_x_mm / kDmMm / (pts.nx - 1) * kDmMm, s.fluid.box_y_mm / kDmMm / (pts.ny - 1) * kDmMm,
          s.fluid.box_z_mm / kDmMm / (pts.nz - 1) * kDmMm};
}

std::string describe_grid(const Scenario& s, const GridPoints& pts) {
  std::ostringstream m;
  m << "fsei.resolution = \"" << s.fsei.resolution << "\" (" << (s.fsei.resolution == "custom" ? "fluid.nx/ny/nz: " : "")
    << pts.nx << " x " << pts.ny << " x " << pts.nz << " points over fluid.box_x/y/z_mm = " << s.fluid.box_x_mm << " x "
    << s.fluid.box_y_mm << " x " << s.fluid.box_z_mm << ")";
  return m.str();
}

// The aortic orifice must span kMinCellsAcrossAorticOrifice cells of the largest spacing.
void check_grid_against_valves(const Scenario& s, const GridPoints& pts, std::vector<std::string>& errors) {
  const auto h = spacing_mm(s, pts);
  const double h_mm = std::max({h[0], h[1], h[2]});
  const double d_mm = s.geometry.aortic_diameter_mm;
  if (d_mm >= kMinCellsAcrossAorticOrifice * h_mm) return;
  const double h_max = d_mm / kMinCellsAcrossAorticOrifice;
  std::ostringstream m;
  m << describe_grid(s, pts) << " is too coarse for the valves: the aortic orifice (geometry.aortic_diameter_mm = "
    << d_mm << ") spans " << d_mm / h_mm << " cells of " << h_mm << " mm; at least " << kMinCellsAcrossAorticOrifice
    << " are needed (spacing <= " << h_max << " mm: at least " << static_cast<int>(std::ceil(s.fluid.box_x_mm / h_max)) + 1
    << " x " << static_cast<int>(std::ceil(s.fluid.box_y_mm / h_max)) + 1 << " x "
    << static_cast<int>(std::ceil(s.fluid.box_z_mm / h_max)) + 1 << " points)";
  errors.push_back(m.str());
}

// A pressure probe's sphere holds a cell centre wherever its centre lies iff its radius is at
// least half a cell's diagonal (ours: the probes' centres come from the built heart, so the
// rule that holds for every centre is the one checked here).
void check_probe_radius(const Scenario& s, const GridPoints& pts, std::vector<std::string>& errors) {
  const auto h = spacing_mm(s, pts);
  const double half_diagonal_mm = 0.5 * std::sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
  if (s.fsei.probe_radius_mm >= half_diagonal_mm) return;
  std::ostringstream m;
  m << "fsei.probe_radius_mm = " << s.fsei.probe_radius_mm << " is less than half a grid cell's diagonal ("
    << half_diagonal_mm << " mm for cells of " << h[0] << " x " << h[1] << " x " << h[2] << " mm at "
    << describe_grid(s, pts) << "): a pressure probe could hold no cell centre; allowed: at least " << half_diagonal_mm
    << " mm at this grid";
  errors.push_back(m.str());
}

}  // namespace

GridPoints fsei_grid_points(const Scenario& s) {
  const std::string& r = s.fsei.resolution;
  if (r == "custom") return {s.fluid.nx, s.fluid.ny, s.fluid.nz};
  // A preset's points are the for the 140-mm box; a box of another height keeps the
  // preset's spacing in z, rounded to the coarser whole number of cells (ours: at 180 mm, coarse
  // is 65 x 65 x 93 and basic 129 x 129 x 186).
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

void check_fsei_rules(const Scenario& s, std::vector<std::string>& errors) {
  check_aortic_pretension(s.fsei, errors);
  check_coupling(s.fsei, errors);
  check_mitral_limiter(s.structure, errors);
  if (s.scene == "fsei") check_electrophysiology(s, errors);
  try {
    const GridPoints pts = fsei_grid_points(s);
    check_grid_against_valves(s, pts, errors);
    check_probe_radius(s, pts, errors);
  } catch (const InputError& e) {
    errors.push_back(e.what());
  }
}

}  // namespace systole::config
