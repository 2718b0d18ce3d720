#pragma once
// The seed's scales (MODEL.md §3) and the conversions of the coupled scene's nondimensional
// fluid quantities to the units its outputs carry: lengths in d_m, velocities in U_m, times in
// d_m / U_m, pressures in ρ U_m².
#include "solver/config/scenario.h"
#include "solver/core/units.h"
#include "solver/grid/grid.h"

namespace systole::scene::fsei {

constexpr double kDmMm = 1000 * units::kSeedLength_m;     // d_m = 24 mm
constexpr double kUmMmPerMs = units::kSeedVelocity_m_s;   // U_m = 0.6 mm/ms (= m/s)
constexpr double kTimeScaleMs = kDmMm / kUmMmPerMs;       // d_m / U_m = 40 ms
constexpr double kMlPerMm3 = 1e-3;

// Nondimensional fluid quantities in the outputs' units, for blood of the scenario's density in
// the grid's box.
struct OutputScales {
  double mmhg_per_unit;        // ρ U² in mmHg
  double pa_per_unit;          // ρ U² in Pa
  double ml_s_per_unit;        // U d² in ml/s
  double kinetic_mj_per_unit;  // ρ U² × the box's volume in mJ (the box mean of ½|u|² → mJ)
  double force_scale_mn;       // ρ U² d² in mN (the markers' loads → the shells' nodes)
};

inline OutputScales output_scales(const config::Scenario& s, const grid::Grid& g) {
  OutputScales o{};
  const double rho = s.fluid.density_kg_per_m3;
  o.mmhg_per_unit = rho * units::kSeedVelocity_m_s * units::kSeedVelocity_m_s / units::kPaPerMmHg;
  o.pa_per_unit = o.mmhg_per_unit * units::kPaPerMmHg;
  o.ml_s_per_unit = kUmMmPerMs * 1e3 * kDmMm * kDmMm * kMlPerMm3;
  o.kinetic_mj_per_unit =
      1e3 * rho * kUmMmPerMs * kUmMmPerMs * (g.lx() * g.ly() * g.lz() * kDmMm * kDmMm * kDmMm * 1e-9);
  o.force_scale_mn = 1e-3 * rho * kUmMmPerMs * kUmMmPerMs * kDmMm * kDmMm;
  return o;
}

}  // namespace systole::scene::fsei
