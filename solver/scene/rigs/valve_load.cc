#include "solver/scene/rigs/valve_load.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/scene/chamber_walls.h"
#include "solver/structure/shell.h"

namespace systole::scene {

namespace {

std::vector<std::string_view> valve_bodies(Valve valve) {
  if (valve == Valve::kAortic)
    return {std::begin(geometry::kAorticCuspBodies), std::end(geometry::kAorticCuspBodies)};
  return {geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody};
}

structure::BodyGroup make_group(const config::Scenario& s, const geometry::LeftHeart& heart, Valve valve,
                                const std::vector<std::string_view>& names, double damping_per_ms) {
  if (!(damping_per_ms >= 0)) throw InputError("valve load: damping_per_ms must be >= 0");
  const structure::ShellMaterials materials = chamber_wall_materials(s);
  structure::ShellOptions o = structure_options(s, heart.plane.z_mm);
  o.damping_per_ms = damping_per_ms;
  std::vector<structure::ShellModel> models;
  for (auto n : names) {
    models.push_back(body_shell(heart.body(n), materials, o));  // pre-strained if it has a rest shape
    if (valve == Valve::kMitral && s.structure.mitral_limiter)  // from the built, closed valve
      models.back().set_displacement_limit(-geometry::Vec3::UnitZ(), s.structure.mitral_limit_mm,
                                           heart.body(n).position_mm);
  }
  return structure::BodyGroup(std::move(models), contact_options(s));
}

}  // namespace

ClosedValveLoad::ClosedValveLoad(const config::Scenario& scenario, Valve valve, double damping_per_ms)
    : valve_(valve),
      heart_(geometry::build_left_heart(scenario.geometry, scenario.fluid)),
      names_(valve_bodies(valve)),
      group_(make_group(scenario, heart_, valve, names_, damping_per_ms)) {}

ValveLoadSample ClosedValveLoad::advance(double step_ms, double pressure_mmhg) {
  if (!(step_ms > 0) || !std::isfinite(pressure_mmhg))
    throw InputError("valve load: step_ms must be > 0 and pressure_mmhg finite (got step_ms = " + std::to_string(step_ms) +
                     ", pressure_mmhg = " + std::to_string(pressure_mmhg) + ")");
  // Leaflet normals face -z (the aorta / atrium side): set_cavity_pressure(p) pushes along -n,
  // i.e. +z, from the aorta into the LV; the LV's pressure on the mitral leaflets pushes -z.
  const double sign = valve_ == Valve::kAortic ? 1.0 : -1.0;
  const double p_kpa = pressure_mmhg * units::kPaPerMmHg * 1e-3;
  for (std::size_t k = 0; k < group_.body_count(); ++k) group_.body(k).set_cavity_pressure(sign * p_kpa);
  group_.advance(step_ms);
  t_ms_ += step_ms;
  return sample(pressure_mmhg);
}

ValveLoadSample ClosedValveLoad::sample(double pressure_mmhg) const {
  ValveLoadSample s;
  s.t_ms = t_ms_;
  s.pressure_mmhg = pressure_mmhg;
  s.max_strain = -1;
  s.min_strain = 1;
  s.stable_step_ms = 1e300;
  for (std::size_t k = 0; k < group_.body_count(); ++k) {
    const auto& x = group_.body(k).positions_mm();
    const auto& x0 = heart_.body(names_[k]).position_mm;
    for (std::size_t i = 0; i < x.size(); ++i) s.max_displacement_mm = std::max(s.max_displacement_mm, (x[i] - x0[i]).norm());
    for (const auto& v : group_.body(k).velocities_mm_per_ms()) s.max_speed_m_s = std::max(s.max_speed_m_s, v.norm());
    for (double e : group_.body(k).edge_strains()) s.max_strain = std::max(s.max_strain, e), s.min_strain = std::min(s.min_strain, e);
    s.stable_step_ms = std::min(s.stable_step_ms, group_.body(k).stable_step_ms());
  }
  s.contact_pairs = group_.contact_stats().active;
  return s;
}

double ClosedValveLoad::mitral_free_edge_gap_mm() const {
  if (valve_ != Valve::kMitral) throw std::logic_error("mitral_free_edge_gap_mm: not the mitral valve");
  double middle_x[2] = {0, 0};
  for (std::size_t k = 0; k < 2; ++k) {
    const auto& x0 = heart_.body(names_[k]).position_mm;
    const auto& x = group_.body(k).positions_mm();
    double deepest = -1e300;
    for (const auto& p : x0) deepest = std::max(deepest, p.z());
    int n = 0;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x0[i].z() > deepest - 3) middle_x[k] += x[i].x(), ++n;
    middle_x[k] /= n;  // n >= 1: the deepest node itself
  }
  return std::abs(middle_x[0] - middle_x[1]);
}

}  // namespace systole::scene
