#pragma once
// Shared by the structure verification tests: a closed isotropic icosphere (no fibre) inflated by
// a cavity pressure and damped to rest; returns its mean radius over R0.
#include <algorithm>
#include <vector>

#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::structure::testing {

// `options` as given, with damping 0.15/ms; stops when every force is below 1e-9 p R0^2 and the
// kinetic energy below 1e-14 uJ, or after 4 s.
inline double inflate_to_rest(int level, double p_kpa, double r0_mm, double s_mm, const ShellMaterials& materials,
                              ShellOptions options) {
  options.damping_per_ms = 0.15;
  ShellModel body(icosphere(r0_mm, level, s_mm, geometry::Tissue::kLvMyocardium, false), materials, options);
  body.set_cavity_pressure(p_kpa);
  for (int k = 0; k < 400; ++k) {
    body.advance(10);
    double fmax = 0;
    for (const auto& f : body.forces_mn()) fmax = std::max(fmax, f.norm());
    if (fmax < 1e-9 * p_kpa * r0_mm * r0_mm && body.energies().kinetic_uj < 1e-14) break;
  }
  double r = 0;
  for (const auto& x : body.positions_mm()) r += x.norm();
  return r / static_cast<double>(body.node_count()) / r0_mm;
}

}  // namespace systole::structure::testing
