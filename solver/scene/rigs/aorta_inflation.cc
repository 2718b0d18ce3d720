#include "solver/scene/rigs/aorta_inflation.h"

#include <algorithm>
#include <cmath>
#include <deque>
#include <string>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/scene/chamber_walls.h"

namespace systole::scene {

namespace {

using geometry::Vec3;

constexpr double kStepMs = 0.1;  // the follower loads are refreshed this often (ours)

double kpa_of_mmhg(double p_mmhg) { return p_mmhg * units::kPaPerMmHg * 1e-3; }

// Sum over the triangles of (1/6) a . (b x c) (mm^3): minus the enclosed volume for the heart's
// inward normals, up to the fixed ends' caps.
double signed_volume_mm3(const geometry::TriMesh& mesh, const std::vector<Vec3>& x) {
  double v = 0;
  for (const auto& t : mesh.tri) v += x[t[0]].dot(x[t[1]].cross(x[t[2]])) / 6.0;
  return v;
}

structure::ShellModel make_aorta(const config::Scenario& s, const geometry::LeftHeart& heart, double damping_per_ms) {
  if (!(damping_per_ms > 0))
    throw InputError("aorta inflation: damping_per_ms = " + std::to_string(damping_per_ms) + " must be > 0");
  if (!s.fsei.aorta.outlet_held)
    throw InputError("aorta inflation needs fsei.aorta.outlet_held = true: the lumen's volume is measured between "
                     "fixed ends");
  structure::ShellOptions o = structure_options(s, heart.plane.z_mm);
  o.damping_per_ms = damping_per_ms;
  const geometry::TriMesh& mesh = heart.body(geometry::kAortaBody);
  structure::ShellModel aorta(mesh, chamber_wall_materials(s), o);
  std::vector<std::int32_t> outlet;  // held as the scenes hold it (fsei_scene.cc)
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if (mesh.region[i] & geometry::kOutflow) outlet.push_back(static_cast<std::int32_t>(i));
  aorta.fix_nodes(outlet);
  return aorta;
}

}  // namespace

AortaInflation::AortaInflation(const config::Scenario& scenario, double ground_pressure_mmhg, double prestress_fraction,
                               double damping_per_ms)
    : heart_(geometry::build_left_heart(scenario.geometry, scenario.fluid)),
      aorta_(make_aorta(scenario, heart_, damping_per_ms)) {
  if (!(prestress_fraction >= 0 && prestress_fraction <= 1))
    throw InputError("aorta inflation: prestress_fraction = " + std::to_string(prestress_fraction) +
                     " must be in [0, 1]");
  if (!(ground_pressure_mmhg >= 0))
    throw InputError("aorta inflation: ground_pressure_mmhg = " + std::to_string(ground_pressure_mmhg) + " must be >= 0");
  const double wall_kpa = prestress_fraction * kpa_of_mmhg(ground_pressure_mmhg);
  if (wall_kpa > 0) {
    prestress_ = structure::membrane_prestress(
        aorta_, structure::pressure_nodal_forces(aorta_.stress_free_mesh(), aorta_.positions_mm(), -wall_kpa,
                                                 geometry::kOutflow));
    aorta_.set_rest_lengths_mm(prestress_.rest_length_mm);
  }
  outer_kpa_ = kpa_of_mmhg(ground_pressure_mmhg) - wall_kpa;
  pressure_mmhg_ = ground_pressure_mmhg;
  signed_volume_built_mm3_ = signed_volume_mm3(heart_.body(geometry::kAortaBody), aorta_.positions_mm());
  advance(kStepMs, pressure_mmhg_);  // loads on; the clock starts
}

double AortaInflation::volume_change_ml() const {
  const double s = signed_volume_mm3(heart_.body(geometry::kAortaBody), aorta_.positions_mm());
  return -(s - signed_volume_built_mm3_) * 1e-3;  // inward normals: the sum is minus the volume
}

void AortaInflation::advance(double step_ms, double inner_pressure_mmhg) {
  // The net follower load: the outer load pushes the wall in, the blood out.
  aorta_.set_external_loads(structure::pressure_nodal_forces(heart_.body(geometry::kAortaBody), aorta_.positions_mm(),
                                                             outer_kpa_ - kpa_of_mmhg(inner_pressure_mmhg),
                                                             geometry::kOutflow));
  aorta_.advance(step_ms);
}

AortaInflationPoint AortaInflation::hold(double pressure_mmhg, double ramp_ms, double max_ms, double settle_ml,
                                         double settle_window_ms) {
  if (!(pressure_mmhg >= 0) || !(ramp_ms >= 0) || !(max_ms > 0) || !(settle_ml > 0) || !(settle_window_ms > 0))
    throw InputError("aorta inflation: hold(pressure_mmhg >= 0, ramp_ms >= 0, max_ms > 0, settle_ml > 0, "
                     "settle_window_ms > 0)");
  const double p_from = pressure_mmhg_;
  const int ramp_steps = static_cast<int>(std::ceil(ramp_ms / kStepMs));
  for (int k = 1; k <= ramp_steps; ++k) advance(kStepMs, p_from + (pressure_mmhg - p_from) * k / ramp_steps);
  pressure_mmhg_ = pressure_mmhg;
  const int window = std::max(1, static_cast<int>(std::lround(settle_window_ms / kStepMs)));
  std::deque<double> recent{volume_change_ml()};
  bool settled = false;
  for (double held = 0; held < max_ms && !settled; held += kStepMs) {
    advance(kStepMs, pressure_mmhg_);
    recent.push_back(volume_change_ml());
    if (static_cast<int>(recent.size()) > window + 1) recent.pop_front();
    settled = static_cast<int>(recent.size()) == window + 1 && std::abs(recent.back() - recent.front()) < settle_ml;
  }
  AortaInflationPoint out = sample();
  out.settled = settled;
  return out;
}

AortaInflationPoint AortaInflation::sample() const {
  AortaInflationPoint s;
  s.pressure_mmhg = pressure_mmhg_;
  s.volume_change_ml = volume_change_ml();
  s.max_strain = -1;
  s.min_strain = 1;
  for (double e : aorta_.edge_strains()) s.max_strain = std::max(s.max_strain, e), s.min_strain = std::min(s.min_strain, e);
  const auto& x = aorta_.positions_mm();
  const auto& x0 = heart_.body(geometry::kAortaBody).position_mm;
  for (std::size_t i = 0; i < x.size(); ++i) s.max_displacement_mm = std::max(s.max_displacement_mm, (x[i] - x0[i]).norm());
  s.time_ms = aorta_.time_ms();
  return s;
}

}  // namespace systole::scene
