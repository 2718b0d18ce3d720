#include "solver/coupling/fluid_module.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::coupling {

FluidModule::FluidModule(fluid::FluidSolver& fluid, ibm::Markers& markers, ibm::DirectForcing& forcing,
                         FluidModuleOptions options)
    : fluid_(fluid), markers_(markers), forcing_(forcing), options_(options), saved_(fluid.slabs()) {
  if (!(options_.time_scale_ms > 0) || !std::isfinite(options_.time_scale_ms)) {
    std::ostringstream m;
    m << "fluid module: time_scale_ms = " << options_.time_scale_ms << " must be > 0 (d_m / U_m in ms)";
    throw InputError(m.str());
  }
  if (!options_.uniform_force_density.allFinite())
    throw InputError("fluid module: uniform_force_density must be finite");
  if (!(options_.carry_over_reference_cfl >= 0 && options_.carry_over_reference_cfl <= 1)) {
    std::ostringstream m;
    m << "fluid module: carry_over_reference_cfl = " << options_.carry_over_reference_cfl
      << " is out of range [0, 1] (0: off; else the CFL target whose step sets the carry-over's rate)";
    throw InputError(m.str());
  }
  // The forcing of eq 3 (and the optional uniform driving force) is the fluid's body force.
  const grid::Slabs& slabs = fluid_.slabs();
  fluid_.set_body_force([this, &slabs](const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
    const ibm::Vec3 g = options_.uniform_force_density;
    double share = 1;  // the step-aware increment share (options_.carry_over_reference_cfl)
    if (options_.carry_over_reference_cfl > 0) {
      const double ref = fluid_.step_at_cfl(options_.carry_over_reference_cfl);
      share = std::min(1.0, fluid_.step_at_cfl(fluid_.parameters().cfl) / ref);
    }
    forcing_.apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, g, share);
    if (g.isZero()) return;
    const grid::Grid& grid = slabs.grid();
    for (int k = 0; k < f.u.k_count(); ++k) {
      const bool wall = slabs.k_begin() + k == 0;  // w at the bottom wall stays 0
      for (int j = 0; j < grid.ny(); ++j)
        for (int i = 0; i < grid.nx(); ++i) {
          f.u(i, j, k) += g.x();
          f.v(i, j, k) += g.y();
          if (!wall) f.w(i, j, k) += g.z();
        }
    }
  });
}

void FluidModule::step(double dt_ms) {
  if (moved_) {
    forcing_.markers_moved();  // rebuilds the stencils of the bodies that moved
    moved_ = false;
  }
  const double t_end = fluid_.time() + dt_ms / options_.time_scale_ms;
  fluid_.advance(t_end);  // lands on t_end when dt_ms is within the limit (header: otherwise short)
}

void FluidModule::set_body_nodes(int body, const std::vector<ibm::Vec3>& position,
                                 const std::vector<ibm::Vec3>& velocity) {
  markers_.set_nodes(body, position, velocity);
  moved_ = true;
}

ibm::MarkerLoads FluidModule::loads(const std::vector<bool>& bodies) const {
  const fluid::Velocity& u = fluid_.velocity();
  return ibm::compute_loads(forcing_.transfer(), {u.u, u.v, u.w}, fluid_.pressure(), fluid_.parameters().reynolds, {},
                            bodies);
}

ibm::WallShear FluidModule::wall_shear() const {
  const fluid::Velocity& u = fluid_.velocity();
  return ibm::wall_shear_stress(forcing_.transfer(), {u.u, u.v, u.w}, fluid_.pressure(), fluid_.parameters().reynolds);
}

}  // namespace systole::coupling
