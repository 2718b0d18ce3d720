#include "solver/fluid/fluid.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/fluid/operators.h"
#include "solver/grid/field_io.h"

namespace systole::fluid {

namespace {
[[noreturn]] void bad(const std::string& field, double value, const std::string& allowed) {
  std::ostringstream m;
  m << "fluid." << field << " = " << value << " is out of range " << allowed;
  throw InputError(m.str());
}
double global_sum(double x, MPI_Comm c) {
  double out = 0;
  MPI_Allreduce(&x, &out, 1, MPI_DOUBLE, MPI_SUM, c);
  return out;
}
double global_max(double x, MPI_Comm c) {
  double out = 0;
  MPI_Allreduce(&x, &out, 1, MPI_DOUBLE, MPI_MAX, c);
  return out;
}
}  // namespace

void validate(const FluidParameters& p, const grid::Grid& g) {
  if (!(p.reynolds > 0 && p.reynolds <= 1e7)) bad("reynolds", p.reynolds, "(0, 1e7]");
  if (!(p.cfl > 0 && p.cfl <= 1))
    bad("cfl", p.cfl, "(0, 1] (explicit AB2 advection is unstable beyond CFL ~ 0.5; 1 is the hard limit)");
  if (!(p.max_dt > 0 && std::isfinite(p.max_dt))) bad("max_dt", p.max_dt, "(0, inf) nondimensional");
  if (p.cfl_rule != "component_maxima" && p.cfl_rule != "per_cell")
    throw InputError("fluid.cfl_rule = '" + p.cfl_rule + "' is unknown; known: component_maxima, per_cell");
  if (!(p.viscous_safety > 0 && p.viscous_safety <= 1)) bad("viscous_safety", p.viscous_safety, "(0, 1]");
  if (!(p.darcy_permeability > 0 && std::isfinite(p.darcy_permeability)))
    bad("darcy_permeability", p.darcy_permeability, "(0, inf)");
  if (!(p.time_scale_s > 0)) bad("time_scale_s", p.time_scale_s, "(0, inf)");
  if (!(p.abort_cfl > 0)) bad("abort_cfl", p.abort_cfl, "(0, inf)");
  if (!(p.abort_energy_growth > 1)) bad("abort_energy_growth", p.abort_energy_growth, "(1, inf)");
  if (!(p.abort_energy_floor >= 0 && std::isfinite(p.abort_energy_floor)))
    bad("abort_energy_floor", p.abort_energy_floor, "[0, inf)");
  if (!(p.abort_min_dt >= 0 && p.abort_min_dt < p.max_dt)) bad("abort_min_dt", p.abort_min_dt, "[0, max_dt)");
  if (p.viscosity_model != "newtonian" && p.viscosity_model != "carreau_yasuda")
    throw InputError("fluid.viscosity_model = '" + p.viscosity_model + "' is unknown; known: newtonian, carreau_yasuda");
  if (p.viscosity_model == "carreau_yasuda") validate(p.carreau_yasuda);
  if (p.subgrid_model != "none" && p.subgrid_model != "vreman")
    throw InputError("fluid.subgrid_model = '" + p.subgrid_model + "' is unknown; known: none, vreman");
  if (!(p.subgrid_constant > 0 && p.subgrid_constant <= 1)) bad("subgrid_constant", p.subgrid_constant, "(0, 1]");
  if (p.subgrid_model != "none" && p.viscosity_model != "newtonian")
    throw InputError("fluid.subgrid_model = '" + p.subgrid_model + "' needs fluid.viscosity_model = newtonian, not '" +
                     p.viscosity_model + "'");
  for (std::size_t r = 0; r < p.darcy_regions.size(); ++r) {
    const DarcyRegion& d = p.darcy_regions[r];
    auto inside = [](double lo, double hi, double l) { return 0 <= lo && lo < hi && hi <= l; };
    if (!inside(d.x_min, d.x_max, g.lx()) || !inside(d.y_min, d.y_max, g.ly()) || !inside(d.z_min, d.z_max, g.lz())) {
      std::ostringstream m;
      m << "fluid.darcy_regions[" << r << "] = [" << d.x_min << "," << d.x_max << "]×[" << d.y_min << ","
        << d.y_max << "]×[" << d.z_min << "," << d.z_max << "] is not a non-empty box inside the fluid box [0,"
        << g.lx() << "]×[0," << g.ly() << "]×[0," << g.lz() << "]";
      throw InputError(m.str());
    }
  }
}

FluidSolver::FluidSolver(const grid::Slabs& slabs, FluidParameters parameters)
    : slabs_(slabs), par_((validate(parameters, slabs.grid()), std::move(parameters))),
      poisson_(std::make_unique<PoissonSolver>(slabs)), vel_(slabs), p_(slabs), phi_(slabs), rhs_(slabs),
      h_(std::make_unique<Velocity>(slabs)), h_prev_(std::make_unique<Velocity>(slabs)) {
  if (par_.viscosity_model == "carreau_yasuda" || par_.subgrid_model != "none")
    nu_ = std::make_unique<grid::CellField>(slabs);
  apply_velocity_boundary_conditions(vel_);
}

FluidSolver::~FluidSolver() = default;

std::size_t FluidSolver::bytes_allocated() const {
  std::size_t fields = 3 * 3 + 3 + (force_ ? 3 : 0) + (nu_ ? 1 : 0);
  return fields * p_.bytes() + poisson_->bytes_allocated();
}

void FluidSolver::set_body_force(BodyForce force) {
  body_force_ = std::move(force);
  if (body_force_ && !force_) force_ = std::make_unique<Velocity>(slabs_);
}

void FluidSolver::apply_velocity_boundary_conditions(Velocity& vel) const {
  grid::exchange_halos(vel.u, slabs_);
  grid::exchange_halos(vel.v, slabs_);
  grid::exchange_halos(vel.w, slabs_);
  const int nx = vel.u.nx(), ny = vel.u.ny(), nzl = vel.u.k_count();
  auto tangential = [&](const Wall& wall, int ghost, int inner) {
    const bool slip = wall.kind == WallKind::free_slip;
    for (int j = -1; j <= ny; ++j)
      for (int i = -1; i <= nx; ++i) {
        vel.u(i, j, ghost) = slip ? vel.u(i, j, inner) : 2 * wall.velocity_x - vel.u(i, j, inner);
        vel.v(i, j, ghost) = slip ? vel.v(i, j, inner) : 2 * wall.velocity_y - vel.v(i, j, inner);
      }
  };
  if (slabs_.owns_bottom_wall()) {
    tangential(par_.bottom_wall, -1, 0);
    for (int j = -1; j <= ny; ++j)
      for (int i = -1; i <= nx; ++i) vel.w(i, j, 0) = 0, vel.w(i, j, -1) = 0;
  }
  if (slabs_.owns_top_wall()) {
    tangential(par_.top_wall, nzl, nzl - 1);
    for (int j = -1; j <= ny; ++j)
      for (int i = -1; i <= nx; ++i) vel.w(i, j, nzl) = 0;
  }
}

void FluidSolver::set_velocity(const VelocityFunction& fu, const VelocityFunction& fv, const VelocityFunction& fw) {
  const grid::Grid& g = slabs_.grid();
  using grid::Location;
  for (int k = 0; k < vel_.u.k_count(); ++k) {
    const int kg = slabs_.k_begin() + k;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        vel_.u(i, j, k) = fu(g.x(Location::x_face, i), g.y(Location::x_face, j), g.z(Location::x_face, kg));
        vel_.v(i, j, k) = fv(g.x(Location::y_face, i), g.y(Location::y_face, j), g.z(Location::y_face, kg));
        vel_.w(i, j, k) = kg == 0 ? 0.0 : fw(g.x(Location::z_face, i), g.y(Location::z_face, j), g.z(Location::z_face, kg));
      }
  }
  apply_velocity_boundary_conditions(vel_);
  project(1.0);
  p_.fill(0.0);
  have_history_ = false;
  dt_prev_ = 0;
  check_stability(0.0);
}

void FluidSolver::set_pressure(const VelocityFunction& fp) {
  const grid::Grid& g = slabs_.grid();
  using grid::Location;
  for (int k = 0; k < p_.k_count(); ++k) {
    const int kg = slabs_.k_begin() + k;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i)
        p_(i, j, k) = fp(g.x(Location::cell, i), g.y(Location::cell, j), g.z(Location::cell, kg));
  }
  grid::exchange_halos(p_, slabs_);
}

double FluidSolver::step_bound(double cfl) const {
  const grid::Grid& g = slabs_.grid();
  double dt = par_.max_dt;
  if (!par_.adaptive_dt) return dt;
  const double rate =
      par_.cfl_rule == "per_cell" ? max_cell_rate_ : max_u_ / g.dx() + max_v_ / g.dy() + max_w_ / g.dz();
  if (rate > 0) dt = std::min(dt, cfl / rate);
  const double nu = max_viscosity();  // Carreau–Yasuda or a subgrid model: the field's largest ν
  const double lam = 4 / (g.dx() * g.dx()) + 4 / (g.dy() * g.dy()) + 4 / (g.dz() * g.dz());
  return std::min(dt, par_.viscous_safety / (nu * lam));
}

double FluidSolver::step_at_cfl(double cfl) const {
  if (!(cfl > 0 && cfl <= 1)) {
    std::ostringstream m;
    m << "fluid: step_at_cfl(cfl = " << cfl << "): the CFL target must be in (0, 1]";
    throw InputError(m.str());
  }
  return step_bound(cfl);
}

double FluidSolver::choose_time_step(double t_limit) const {
  const double dt = step_bound(par_.cfl);
  if (par_.adaptive_dt) {
    if (dt < par_.abort_min_dt) {
      std::ostringstream place, what;
      place << "step " << steps_ << ", fastest cell " << fastest_cell() << " (max |u|,|v|,|w| = " << max_u_ << ", "
            << max_v_ << ", " << max_w_ << ")";
      what << "the stable step " << dt << " fell below abort_min_dt " << par_.abort_min_dt
           << " (the velocities or the viscosity grew " << par_.max_dt / dt << "-fold past those of the largest step)";
      throw InstabilityError("fluid", place.str(), time_ * par_.time_scale_s, what.str());
    }
  }
  // Land exactly on t_limit (round-off in t is absorbed); a leftover below ½Δt is avoided by
  // splitting the last 1.5Δt evenly (ours).
  const double remaining = t_limit - time_;
  if (dt >= remaining * (1 - 1e-9)) return remaining;
  if (remaining < 1.5 * dt) return 0.5 * remaining;
  return dt;
}

// ---- the explicit terms, eq 1–2: H = −∇·(u u) + Re⁻¹ ∇²u, at each velocity's own faces ----
// Carreau–Yasuda or a subgrid model: H = −∇·(uu) + ∇·[ν(∇u + ∇uᵀ)], ν from update_viscosity().
void FluidSolver::compute_explicit_terms() {
  if (nu_) {
    explicit_terms_kernel<false>();
    add_variable_viscous_term();
  } else {
    explicit_terms_kernel<true>();
  }
}

template <bool kNewtonianViscous>
void FluidSolver::explicit_terms_kernel() {
  const grid::Grid& g = slabs_.grid();
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const double nu = kNewtonianViscous ? 1 / par_.reynolds : 0.0;
  const double cx = nu * idx * idx, cy = nu * idy * idy, cz = nu * idz * idz;
  const auto sj = vel_.u.stride_j(), sk = vel_.u.stride_k();
  const int nx = g.nx(), ny = g.ny();
  for (int k = 0; k < vel_.u.k_count(); ++k) {
    const bool bottom_wall_face = slabs_.k_begin() + k == 0;
    for (int j = 0; j < ny; ++j) {
      const auto row = vel_.u.index(0, j, k);
      const double* u = vel_.u.data() + row;
      const double* v = vel_.v.data() + row;
      const double* w = vel_.w.data() + row;
      double* hu = h_->u.data() + row;
      double* hv = h_->v.data() + row;
      double* hw = h_->w.data() + row;
      // u at x-face (i,j,k)
      for (int i = 0; i < nx; ++i) {
        const double ue = 0.5 * (u[i + 1] + u[i]), uw = 0.5 * (u[i] + u[i - 1]);
        const double vn = 0.5 * (v[i + sj] + v[i - 1 + sj]), vs = 0.5 * (v[i] + v[i - 1]);
        const double wt = 0.5 * (w[i + sk] + w[i - 1 + sk]), wb = 0.5 * (w[i] + w[i - 1]);
        const double adv = (ue * ue - uw * uw) * idx +
                           (vn * 0.5 * (u[i + sj] + u[i]) - vs * 0.5 * (u[i] + u[i - sj])) * idy +
                           (wt * 0.5 * (u[i + sk] + u[i]) - wb * 0.5 * (u[i] + u[i - sk])) * idz;
        const double lap = cx * (u[i + 1] - 2 * u[i] + u[i - 1]) + cy * (u[i + sj] - 2 * u[i] + u[i - sj]) +
                           cz * (u[i + sk] - 2 * u[i] + u[i - sk]);
        hu[i] = kNewtonianViscous ? lap - adv : -adv;
      }
      // v at y-face (i,j,k)
      for (int i = 0; i < nx; ++i) {
        const double ue = 0.5 * (u[i + 1] + u[i + 1 - sj]), uw = 0.5 * (u[i] + u[i - sj]);
        const double vn = 0.5 * (v[i + sj] + v[i]), vs = 0.5 * (v[i] + v[i - sj]);
        const double wt = 0.5 * (w[i + sk] + w[i + sk - sj]), wb = 0.5 * (w[i] + w[i - sj]);
        const double adv = (ue * 0.5 * (v[i + 1] + v[i]) - uw * 0.5 * (v[i] + v[i - 1])) * idx +
                           (vn * vn - vs * vs) * idy +
                           (wt * 0.5 * (v[i + sk] + v[i]) - wb * 0.5 * (v[i] + v[i - sk])) * idz;
        const double lap = cx * (v[i + 1] - 2 * v[i] + v[i - 1]) + cy * (v[i + sj] - 2 * v[i] + v[i - sj]) +
                           cz * (v[i + sk] - 2 * v[i] + v[i - sk]);
        hv[i] = kNewtonianViscous ? lap - adv : -adv;
      }
      // w at z-face (i,j,k); the wall face keeps w = 0
      if (bottom_wall_face) {
        for (int i = 0; i < nx; ++i) hw[i] = 0;
        continue;
      }
      for (int i = 0; i < nx; ++i) {
        const double ue = 0.5 * (u[i + 1] + u[i + 1 - sk]), uw = 0.5 * (u[i] + u[i - sk]);
        const double vn = 0.5 * (v[i + sj] + v[i + sj - sk]), vs = 0.5 * (v[i] + v[i - sk]);
        const double wt = 0.5 * (w[i + sk] + w[i]), wb = 0.5 * (w[i] + w[i - sk]);
        const double adv = (ue * 0.5 * (w[i + 1] + w[i]) - uw * 0.5 * (w[i] + w[i - 1])) * idx +
                           (vn * 0.5 * (w[i + sj] + w[i]) - vs * 0.5 * (w[i] + w[i - sj])) * idy +
                           (wt * wt - wb * wb) * idz;
        const double lap = cx * (w[i + 1] - 2 * w[i] + w[i - 1]) + cy * (w[i + sj] - 2 * w[i] + w[i - sj]) +
                           cz * (w[i + sk] - 2 * w[i] + w[i - sk]);
        hw[i] = kNewtonianViscous ? lap - adv : -adv;
      }
    }
  }
}

// ---- Carreau–Yasuda viscosity, or the Vreman subgrid model (viscosity.h) --------------------
// ν(γ̇), or 1/Re + ν_e(∇u), at the cell centres from the current velocity (halos and wall ghosts valid), then the
// halo layer: neighbour slabs and periodic x, y by exchange; at a no-slip wall the ghost cell
// takes the linear extrapolation 2ν₀ − ν₁ (ours: the wall-edge average is then ν at the wall to
// second order), clamped to [ν∞, ν0] (Vreman: to ≥ 1/Re); at a free-slip wall the mirror value ν₀ (the flow is
// symmetric there). nu_max_ is the global maximum, ghosts included: it limits the next Δt.
void FluidSolver::update_viscosity() { nu_max_ = global_max(compute_viscosity(*nu_), slabs_.comm()); }

double FluidSolver::compute_viscosity(grid::CellField& nu) const {
  const grid::Grid& g = slabs_.grid();
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const CarreauYasuda& law = par_.carreau_yasuda;
  const bool vreman = par_.subgrid_model == "vreman";
  const double nu_molecular = 1 / par_.reynolds, c = par_.subgrid_constant;
  const auto sj = nu.stride_j(), sk = nu.stride_k();
  const double *u = vel_.u.data(), *v = vel_.v.data(), *w = vel_.w.data();
  double* out = nu.data();
  for (int k = 0; k < nu.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = nu.index(0, j, k);
      if (vreman)
        for (int i = 0; i < g.nx(); ++i)
          out[row + i] = nu_molecular + vreman_eddy_viscosity(velocity_gradient_at_cell(u, v, w, row + i, sj, sk, idx,
                                                                                        idy, idz),
                                                              g.dx(), g.dy(), g.dz(), c);
      else
        for (int i = 0; i < g.nx(); ++i)
          out[row + i] =
              law.from_shear_rate_squared(strain_rate_squared_at_cell(u, v, w, row + i, sj, sk, idx, idy, idz));
    }
  grid::exchange_halos(nu, slabs_);
  // The wall ghosts' bounds: the law's range; with a subgrid model at least the molecular ν
  // (ours: the extrapolated eddy part is cut at zero, never negative).
  const double lo = vreman ? nu_molecular : std::min(law.nu_inf, law.nu0),
               hi = vreman ? std::numeric_limits<double>::infinity() : std::max(law.nu_inf, law.nu0);
  auto ghost = [&](const Wall& wall, int g_k, int k0, int k1) {
    for (int j = -1; j <= g.ny(); ++j)
      for (int i = -1; i <= g.nx(); ++i)
        nu(i, j, g_k) = wall.kind == WallKind::free_slip ? nu(i, j, k0)
                                                         : std::clamp(2 * nu(i, j, k0) - nu(i, j, k1), lo, hi);
  };
  const int nzl = nu.k_count();
  if (slabs_.owns_bottom_wall()) ghost(par_.bottom_wall, -1, 0, 1);
  if (slabs_.owns_top_wall()) ghost(par_.top_wall, nzl, nzl - 1, nzl - 2);
  double m = 0;
  for (int k = -1; k <= nzl; ++k)
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) m = std::max(m, nu(i, j, k));
  return m;
}

// The exact discrete energy sink of add_variable_viscous_term (summation by parts): the volume
// mean of 2ν(S_xx² + S_yy² + S_zz²) at the cells plus ν_edge (2S_ab)² at the cell edges, the
// edges on a wall weighted ½ (they bound half a cell). Collective (ν needs its halos).
double FluidSolver::variable_viscosity_dissipation() const {
  const grid::Grid& g = slabs_.grid();
  grid::CellField nu(slabs_);
  compute_viscosity(nu);
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const auto sj = nu.stride_j(), sk = nu.stride_k();
  const double *u = vel_.u.data(), *v = vel_.v.data(), *w = vel_.w.data(), *n = nu.data();
  auto sq = [](double x) { return x * x; };
  double sum = 0;
  const int nzl = nu.k_count();
  // z-edge levels owned here: k = 0 .. nzl−1, plus the top wall level nzl on the top slab.
  for (int k = 0; k <= nzl; ++k) {
    const int kg = slabs_.k_begin() + k;
    if (k == nzl && !slabs_.owns_top_wall()) break;
    const double weight = (kg == 0 || kg == g.nz()) ? 0.5 : 1.0;
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = nu.index(0, j, k);
      for (int i = 0; i < g.nx(); ++i) {
        const auto q = row + i;
        if (k < nzl) {
          const double sxx = (u[q + 1] - u[q]) * idx, syy = (v[q + sj] - v[q]) * idy, szz = (w[q + sk] - w[q]) * idz;
          sum += 2 * n[q] * (sxx * sxx + syy * syy + szz * szz);
          // xy-edge (i, j) at this cell level
          sum += 0.25 * (n[q] + n[q - 1] + n[q - sj] + n[q - 1 - sj]) *
                 sq((u[q] - u[q - sj]) * idy + (v[q] - v[q - 1]) * idx);
        }
        // xz-edge (i, k) and yz-edge (j, k) at the z level of face k
        sum += weight * 0.25 * (n[q] + n[q - 1] + n[q - sk] + n[q - 1 - sk]) *
               sq((u[q] - u[q - sk]) * idz + (w[q] - w[q - 1]) * idx);
        sum += weight * 0.25 * (n[q] + n[q - sj] + n[q - sk] + n[q - sj - sk]) *
               sq((v[q] - v[q - sk]) * idz + (w[q] - w[q - sj]) * idy);
      }
    }
  }
  return global_sum(sum, slabs_.comm()) / static_cast<double>(g.cells());
}

// H += ∇·[ν(∇u + ∇uᵀ)] in divergence form on the MAC grid: normal stresses 2ν∂u_a/∂x_a at the
// cell centres, shear stresses ν(∂u_a/∂x_b + ∂u_b/∂x_a) at the cell edges with ν averaged from
// the four cells sharing the edge. With ν constant it equals ν∇²u + ν∇(∇·u), i.e. the
// Newtonian term up to the round-off divergence the projection leaves.
void FluidSolver::add_variable_viscous_term() {
  const grid::Grid& g = slabs_.grid();
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const auto sj = vel_.u.stride_j(), sk = vel_.u.stride_k();
  const int nx = g.nx(), ny = g.ny();
  for (int k = 0; k < vel_.u.k_count(); ++k) {
    const bool bottom_wall_face = slabs_.k_begin() + k == 0;
    for (int j = 0; j < ny; ++j) {
      const auto row = vel_.u.index(0, j, k);
      const double* u = vel_.u.data() + row;
      const double* v = vel_.v.data() + row;
      const double* w = vel_.w.data() + row;
      const double* nu = nu_->data() + row;
      double* hu = h_->u.data() + row;
      double* hv = h_->v.data() + row;
      double* hw = h_->w.data() + row;
      // u at x-face (i,j,k): τxx at cells i−1, i; τxy at xy-edges (i,j), (i,j+1); τxz at xz-edges (i,k), (i,k+1).
      for (int i = 0; i < nx; ++i) {
        const double txx_e = 2 * nu[i] * (u[i + 1] - u[i]) * idx;
        const double txx_w = 2 * nu[i - 1] * (u[i] - u[i - 1]) * idx;
        const double nu_n = 0.25 * (nu[i + sj] + nu[i - 1 + sj] + nu[i] + nu[i - 1]);
        const double nu_s = 0.25 * (nu[i] + nu[i - 1] + nu[i - sj] + nu[i - 1 - sj]);
        const double txy_n = nu_n * ((u[i + sj] - u[i]) * idy + (v[i + sj] - v[i - 1 + sj]) * idx);
        const double txy_s = nu_s * ((u[i] - u[i - sj]) * idy + (v[i] - v[i - 1]) * idx);
        const double nu_t = 0.25 * (nu[i + sk] + nu[i - 1 + sk] + nu[i] + nu[i - 1]);
        const double nu_b = 0.25 * (nu[i] + nu[i - 1] + nu[i - sk] + nu[i - 1 - sk]);
        const double txz_t = nu_t * ((u[i + sk] - u[i]) * idz + (w[i + sk] - w[i - 1 + sk]) * idx);
        const double txz_b = nu_b * ((u[i] - u[i - sk]) * idz + (w[i] - w[i - 1]) * idx);
        hu[i] += (txx_e - txx_w) * idx + (txy_n - txy_s) * idy + (txz_t - txz_b) * idz;
      }
      // v at y-face (i,j,k): τxy at xy-edges (i,j), (i+1,j); τyy at cells j−1, j; τyz at yz-edges (j,k), (j,k+1).
      for (int i = 0; i < nx; ++i) {
        const double nu_e = 0.25 * (nu[i + 1] + nu[i] + nu[i + 1 - sj] + nu[i - sj]);
        const double nu_w = 0.25 * (nu[i] + nu[i - 1] + nu[i - sj] + nu[i - 1 - sj]);
        const double txy_e = nu_e * ((u[i + 1] - u[i + 1 - sj]) * idy + (v[i + 1] - v[i]) * idx);
        const double txy_w = nu_w * ((u[i] - u[i - sj]) * idy + (v[i] - v[i - 1]) * idx);
        const double tyy_n = 2 * nu[i] * (v[i + sj] - v[i]) * idy;
        const double tyy_s = 2 * nu[i - sj] * (v[i] - v[i - sj]) * idy;
        const double nu_t = 0.25 * (nu[i + sk] + nu[i + sk - sj] + nu[i] + nu[i - sj]);
        const double nu_b = 0.25 * (nu[i] + nu[i - sj] + nu[i - sk] + nu[i - sj - sk]);
        const double tyz_t = nu_t * ((v[i + sk] - v[i]) * idz + (w[i + sk] - w[i + sk - sj]) * idy);
        const double tyz_b = nu_b * ((v[i] - v[i - sk]) * idz + (w[i] - w[i - sj]) * idy);
        hv[i] += (txy_e - txy_w) * idx + (tyy_n - tyy_s) * idy + (tyz_t - tyz_b) * idz;
      }
      if (bottom_wall_face) continue;  // the wall face keeps w = 0 (H = 0 there)
      // w at z-face (i,j,k): τxz at xz-edges (i,k), (i+1,k); τyz at yz-edges (j,k), (j+1,k); τzz at cells k−1, k.
      for (int i = 0; i < nx; ++i) {
        const double nu_e = 0.25 * (nu[i + 1] + nu[i] + nu[i + 1 - sk] + nu[i - sk]);
        const double nu_w = 0.25 * (nu[i] + nu[i - 1] + nu[i - sk] + nu[i - 1 - sk]);
        const double txz_e = nu_e * ((u[i + 1] - u[i + 1 - sk]) * idz + (w[i + 1] - w[i]) * idx);
        const double txz_w = nu_w * ((u[i] - u[i - sk]) * idz + (w[i] - w[i - 1]) * idx);
        const double nu_n = 0.25 * (nu[i + sj] + nu[i] + nu[i + sj - sk] + nu[i - sk]);
        const double nu_s = 0.25 * (nu[i] + nu[i - sj] + nu[i - sk] + nu[i - sj - sk]);
        const double tyz_n = nu_n * ((v[i + sj] - v[i + sj - sk]) * idz + (w[i + sj] - w[i]) * idy);
        const double tyz_s = nu_s * ((v[i] - v[i - sk]) * idz + (w[i] - w[i - sj]) * idy);
        const double tzz_t = 2 * nu[i] * (w[i + sk] - w[i]) * idz;
        const double tzz_b = 2 * nu[i - sk] * (w[i] - w[i - sk]) * idz;
        hw[i] += (txz_e - txz_w) * idx + (tyz_n - tyz_s) * idy + (tzz_t - tzz_b) * idz;
      }
    }
  }
}

// û = uⁿ + Δt (γ Hⁿ + ρ Hⁿ⁻¹) − α Δt ∇pⁿ, in place (eq 2 with the viscous term inside H).
void FluidSolver::predict(double dt, double gamma, double rho) {
  const grid::Grid& g = slabs_.grid();
  const double alpha = gamma + rho;  // = 1 for AB2
  const double cx = alpha * dt / g.dx(), cy = alpha * dt / g.dy(), cz = alpha * dt / g.dz();
  const double a = dt * gamma, b = dt * rho;
  const auto sj = p_.stride_j(), sk = p_.stride_k();
  for (int k = 0; k < vel_.u.k_count(); ++k) {
    const bool wall_face = slabs_.k_begin() + k == 0;
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = p_.index(0, j, k);
      const double* p = p_.data() + row;
      double* u = vel_.u.data() + row;
      double* v = vel_.v.data() + row;
      double* w = vel_.w.data() + row;
      const double *hu = h_->u.data() + row, *hv = h_->v.data() + row, *hw = h_->w.data() + row;
      const double *gu = h_prev_->u.data() + row, *gv = h_prev_->v.data() + row, *gw = h_prev_->w.data() + row;
      for (int i = 0; i < g.nx(); ++i) {
        u[i] += a * hu[i] + b * gu[i] - cx * (p[i] - p[i - 1]);
        v[i] += a * hv[i] + b * gv[i] - cy * (p[i] - p[i - sj]);
      }
      if (!wall_face)
        for (int i = 0; i < g.nx(); ++i) w[i] += a * hw[i] + b * gw[i] - cz * (p[i] - p[i - sk]);
    }
  }
}

void FluidSolver::add_body_force(double dt) {
  if (!body_force_) return;
  apply_velocity_boundary_conditions(vel_);
  force_->u.fill(0);
  force_->v.fill(0);
  force_->w.fill(0);
  body_force_(StepContext{time_, dt, steps_}, vel_, *force_);
  const std::size_t n = p_.size();
  double *u = vel_.u.data(), *v = vel_.v.data(), *w = vel_.w.data();
  const double *fu = force_->u.data(), *fv = force_->v.data(), *fw = force_->w.data();
  for (std::size_t q = 0; q < n; ++q) u[q] += dt * fu[q], v[q] += dt * fv[q];
  // w on the wall faces stays 0 whatever the hook wrote there.
  for (int k = 0; k < vel_.w.k_count(); ++k) {
    if (slabs_.k_begin() + k == 0) continue;
    for (int j = 0; j < p_.ny(); ++j) {
      const auto row = p_.index(0, j, k);
      for (int i = 0; i < p_.nx(); ++i) w[row + i] += dt * fw[row + i];
    }
  }
}

// Point-implicit Darcy sink (ours): ∂u/∂t = −u/k integrated implicitly over the step,
// u* ← u*/(1 + Δt/k), stable for the seed's k = 0.001 at any Δt (explicit needs Δt < 2k).
void FluidSolver::apply_darcy_sink(double dt) {
  if (par_.darcy_regions.empty()) return;
  const grid::Grid& g = slabs_.grid();
  const double factor = 1.0 / (1.0 + dt / par_.darcy_permeability);
  using grid::Location;
  auto in = [](const DarcyRegion& d, double x, double y, double z) {
    return x >= d.x_min && x <= d.x_max && y >= d.y_min && y <= d.y_max && z >= d.z_min && z <= d.z_max;
  };
  for (const DarcyRegion& d : par_.darcy_regions)
    for (int k = 0; k < p_.k_count(); ++k) {
      const int kg = slabs_.k_begin() + k;
      for (int j = 0; j < g.ny(); ++j)
        for (int i = 0; i < g.nx(); ++i) {
          if (in(d, g.x(Location::x_face, i), g.y(Location::x_face, j), g.z(Location::x_face, kg))) vel_.u(i, j, k) *= factor;
          if (in(d, g.x(Location::y_face, i), g.y(Location::y_face, j), g.z(Location::y_face, kg))) vel_.v(i, j, k) *= factor;
          if (in(d, g.x(Location::z_face, i), g.y(Location::z_face, j), g.z(Location::z_face, kg))) vel_.w(i, j, k) *= factor;
        }
    }
}

// Eq 9 with α = γ + ρ = 1: ∇²φ = ∇·u*/(αΔt), u = u* − αΔt ∇φ. Leaves φ in phi_ with halos.
void FluidSolver::project(double dt) {
  apply_velocity_boundary_conditions(vel_);
  divergence_at_cell(slabs_.grid(), vel_.u, vel_.v, vel_.w, 1.0 / dt, rhs_);
  poisson_->solve(rhs_, phi_);
  grid::exchange_halos(phi_, slabs_);
  subtract_gradient_at_faces(slabs_, phi_, dt, vel_.u, vel_.v, vel_.w);
  apply_velocity_boundary_conditions(vel_);
}

// Eq 10 without the Crank–Nicolson term (viscous term explicit, see README): p ← p + φ.
void FluidSolver::update_pressure() {
  double* p = p_.data();
  const double* phi = phi_.data();
  for (std::size_t q = 0; q < p_.size(); ++q) p[q] += phi[q];
}

void FluidSolver::check_stability(double dt) {
  const grid::Grid& g = slabs_.grid();
  double mu = 0, mv = 0, mw = 0, rate = 0, ke = 0, bad = 0;
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = p_.index(0, j, k);
      const double *u = vel_.u.data() + row, *v = vel_.v.data() + row, *w = vel_.w.data() + row;
      for (int i = 0; i < g.nx(); ++i) {
        const double au = std::abs(u[i]), av = std::abs(v[i]), aw = std::abs(w[i]);
        mu = std::max(mu, au);
        mv = std::max(mv, av);
        mw = std::max(mw, aw);
        rate = std::max(rate, au * idx + av * idy + aw * idz);
        ke += u[i] * u[i] + v[i] * v[i] + w[i] * w[i];
      }
    }
  if (!std::isfinite(ke)) bad = 1;
  double local[5] = {mu, mv, mw, bad, rate}, global[5];
  MPI_Allreduce(local, global, 5, MPI_DOUBLE, MPI_MAX, slabs_.comm());
  const double ke_new = 0.5 * global_sum(ke, slabs_.comm()) / static_cast<double>(g.cells());
  const double time_s = time_ * par_.time_scale_s;
  if (global[3] > 0) {
    // Locate the first non-finite face value (lowest global index over all ranks).
    long long first = std::numeric_limits<long long>::max();
    int component = 0;
    for (int c = 0; c < 3 && first == std::numeric_limits<long long>::max(); ++c) {
      const double* f = c == 0 ? vel_.u.data() : c == 1 ? vel_.v.data() : vel_.w.data();
      for (int k = 0; k < p_.k_count() && first == std::numeric_limits<long long>::max(); ++k)
        for (int j = 0; j < g.ny(); ++j)
          for (int i = 0; i < g.nx(); ++i)
            if (!std::isfinite(f[p_.index(i, j, k)]) && first == std::numeric_limits<long long>::max()) {
              first = (static_cast<long long>(c) * g.nz() + slabs_.k_begin() + k) * g.ny() * g.nx() +
                      static_cast<long long>(j) * g.nx() + i;
              component = c;
            }
    }
    long long where = 0;
    MPI_Allreduce(&first, &where, 1, MPI_LONG_LONG, MPI_MIN, slabs_.comm());
    component = static_cast<int>(where / g.cells());
    const long long rest = where % g.cells();
    const int i = static_cast<int>(rest % g.nx()), j = static_cast<int>((rest / g.nx()) % g.ny()),
              k = static_cast<int>(rest / (static_cast<long long>(g.nx()) * g.ny()));
    std::ostringstream place;
    place << "step " << steps_ << ", " << "uvw"[component] << " at " << grid::to_string(static_cast<grid::Location>(component + 1))
          << " (i,j,k) = (" << i << "," << j << "," << k << ")";
    throw InstabilityError("fluid", place.str(), time_s, "non-finite velocity");
  }
  const double cfl = dt * (global[0] / g.dx() + global[1] / g.dy() + global[2] / g.dz());
  if (dt > 0 && cfl > par_.abort_cfl) {
    std::ostringstream place, what;
    place << "step " << steps_ << ", fastest cell " << fastest_cell() << " (max |u|,|v|,|w| = " << global[0] << ", "
          << global[1] << ", " << global[2] << ")";
    what << "realised CFL " << cfl << " > abort_cfl " << par_.abort_cfl << " with dt = " << dt;
    throw InstabilityError("fluid", place.str(), time_s, what.str());
  }
  if (dt > 0 && kinetic_energy_ > 0 && ke_new > par_.abort_energy_floor &&
      ke_new > par_.abort_energy_growth * kinetic_energy_) {
    std::ostringstream place, what;
    place << "step " << steps_ << ", fastest cell " << fastest_cell() << " (max |u|,|v|,|w| = " << global[0] << ", "
          << global[1] << ", " << global[2] << ")";
    what << "kinetic energy grew by a factor " << ke_new / kinetic_energy_ << " > abort_energy_growth "
         << par_.abort_energy_growth << " in one step of dt = " << dt;
    throw InstabilityError("fluid", place.str(), time_s, what.str());
  }
  max_u_ = global[0];
  max_v_ = global[1];
  max_w_ = global[2];
  max_cell_rate_ = global[4];
  kinetic_energy_ = ke_new;
}

std::string FluidSolver::fastest_cell() const {
  const grid::Grid& g = slabs_.grid();
  struct {
    double value;
    int rank;
  } local{-1, slabs_.rank()}, global{};
  int at[3] = {0, 0, 0};
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        const double c = std::abs(vel_.u(i, j, k)) / g.dx() + std::abs(vel_.v(i, j, k)) / g.dy() +
                         std::abs(vel_.w(i, j, k)) / g.dz();
        if (c > local.value || !std::isfinite(c)) {
          local.value = std::isfinite(c) ? c : std::numeric_limits<double>::max();
          at[0] = i, at[1] = j, at[2] = slabs_.k_begin() + k;
        }
      }
  MPI_Allreduce(&local, &global, 1, MPI_DOUBLE_INT, MPI_MAXLOC, slabs_.comm());
  MPI_Bcast(at, 3, MPI_INT, global.rank, slabs_.comm());
  std::ostringstream out;
  out.precision(4);
  const double mm = par_.length_scale_mm;
  out << "(i,j,k) = (" << at[0] << "," << at[1] << "," << at[2] << ") at (" << g.x(grid::Location::cell, at[0]) * mm << ", "
      << g.y(grid::Location::cell, at[1]) * mm << ", " << g.z(grid::Location::cell, at[2]) * mm << ") mm";
  return out.str();
}

double FluidSolver::advance(double t_limit) {
  if (nu_) update_viscosity();  // ν(γ̇ⁿ): the explicit term and the Δt limit need it
  const double dt = choose_time_step(t_limit);
  // AB2 coefficients for a variable step (ours; γ = 3/2, ρ = −1/2 when Δt is constant). The
  // first step is forward Euler (γ = 1, ρ = 0).
  double gamma = 1, rho = 0;
  if (have_history_) {
    const double r = dt / dt_prev_;
    gamma = 1 + 0.5 * r;
    rho = -0.5 * r;
  }
  compute_explicit_terms();     // Hⁿ from uⁿ (halos and walls valid)
  predict(dt, gamma, rho);      // û (eq 2)
  add_body_force(dt);           // u* = û + Δt f (eq 8)
  apply_darcy_sink(dt);         // −u/k in the afterload region (MODEL.md §2)
  project(dt);                  // eq 9
  update_pressure();            // eq 10
  std::swap(h_, h_prev_);
  have_history_ = true;
  dt_prev_ = dt;
  time_ += dt;
  ++steps_;
  check_stability(dt);
  return dt;
}

long FluidSolver::advance_to(double t_end) {
  long n = 0;
  while (time_ < t_end * (1 - 1e-14) - 1e-300) {
    advance(t_end);
    ++n;
  }
  return n;
}

FlowDiagnostics FluidSolver::diagnostics() const {
  const grid::Grid& g = slabs_.grid();
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const auto sj = p_.stride_j(), sk = p_.stride_k();
  double grad2 = 0;
  const int nzl = p_.k_count();
  for (int k = 0; k < nzl; ++k) {
    const int kg = slabs_.k_begin() + k;
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = p_.index(0, j, k);
      const double *u = vel_.u.data() + row, *v = vel_.v.data() + row, *w = vel_.w.data() + row;
      for (int i = 0; i < g.nx(); ++i) {
        auto sq = [](double x) { return x * x; };
        // forward differences in x, y; z differences between k and k+1 (cells) plus the wall
        // difference below cell 0 for u, v (ghost − interior over Δz).
        // Forward differences; across a no-slip wall (ghost − interior) the pair stands for
        // half a cell and is weighted ½, which makes ε the exact discrete energy sink −ν⟨u·∇²u⟩.
        const double top = (kg == g.nz() - 1) ? 0.5 : 1.0;
        grad2 += sq((u[i + 1] - u[i]) * idx) + sq((u[i + sj] - u[i]) * idy) + top * sq((u[i + sk] - u[i]) * idz);
        grad2 += sq((v[i + 1] - v[i]) * idx) + sq((v[i + sj] - v[i]) * idy) + top * sq((v[i + sk] - v[i]) * idz);
        grad2 += sq((w[i + 1] - w[i]) * idx) + sq((w[i + sj] - w[i]) * idy) + sq((w[i + sk] - w[i]) * idz);
        if (kg == 0) grad2 += 0.5 * (sq((u[i] - u[i - sk]) * idz) + sq((v[i] - v[i - sk]) * idz));
      }
    }
  }
  FlowDiagnostics d;
  d.kinetic_energy = kinetic_energy_;
  d.dissipation = global_sum(grad2, slabs_.comm()) / static_cast<double>(g.cells()) / par_.reynolds;
  if (nu_) d.dissipation = variable_viscosity_dissipation();
  d.max_divergence = global_max(max_abs_divergence_local(g, vel_.u, vel_.v, vel_.w), slabs_.comm());
  d.max_speed = std::max({max_u_, max_v_, max_w_});
  return d;
}

std::vector<double> FluidSolver::volume_flux_x() const {
  const grid::Grid& g = slabs_.grid();
  std::vector<double> local(g.nx(), 0.0), global(g.nx(), 0.0);
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) local[i] += vel_.u(i, j, k) * g.dy() * g.dz();
  MPI_Allreduce(local.data(), global.data(), g.nx(), MPI_DOUBLE, MPI_SUM, slabs_.comm());
  return global;
}

void FluidSolver::write_checkpoint(const std::filesystem::path& file) const {
  grid::FieldFile f(file, slabs_, grid::FieldFile::Mode::create);
  f.write("u", vel_.u);
  f.write("v", vel_.v);
  f.write("w", vel_.w);
  f.write("p", p_);
  f.write("h_prev_u", h_prev_->u);
  f.write("h_prev_v", h_prev_->v);
  f.write("h_prev_w", h_prev_->w);
  f.write_attribute("time", time_);
  f.write_attribute("steps", static_cast<double>(steps_));
  f.write_attribute("dt_prev", dt_prev_);
  f.write_attribute("have_history", have_history_ ? 1.0 : 0.0);
  f.write_attribute("kinetic_energy", kinetic_energy_);
  f.write_attribute("reynolds", par_.reynolds);
}

void FluidSolver::restore_checkpoint(const std::filesystem::path& file) {
  grid::FieldFile f(file, slabs_, grid::FieldFile::Mode::read);
  if (f.read_attribute("reynolds") != par_.reynolds)
    throw InputError("checkpoint " + file.string() + " has reynolds = " + std::to_string(f.read_attribute("reynolds")) +
                     ", this solver " + std::to_string(par_.reynolds));
  f.read("u", vel_.u);
  f.read("v", vel_.v);
  f.read("w", vel_.w);
  f.read("p", p_);
  f.read("h_prev_u", h_prev_->u);
  f.read("h_prev_v", h_prev_->v);
  f.read("h_prev_w", h_prev_->w);
  time_ = f.read_attribute("time");
  steps_ = static_cast<long>(f.read_attribute("steps"));
  dt_prev_ = f.read_attribute("dt_prev");
  have_history_ = f.read_attribute("have_history") != 0;
  apply_velocity_boundary_conditions(vel_);
  grid::exchange_halos(p_, slabs_);
  kinetic_energy_ = 0;
  check_stability(0.0);  // restores the velocity maxima that pick the next Δt
  kinetic_energy_ = f.read_attribute("kinetic_energy");
}

void FluidSolver::save_state(State& out) const {
  out.vel.u = vel_.u;
  out.vel.v = vel_.v;
  out.vel.w = vel_.w;
  out.h_prev.u = h_prev_->u;
  out.h_prev.v = h_prev_->v;
  out.h_prev.w = h_prev_->w;
  out.p = p_;
  out.time = time_;
  out.dt_prev = dt_prev_;
  out.kinetic_energy = kinetic_energy_;
  out.nu_max = nu_max_;
  out.max_u = max_u_;
  out.max_v = max_v_;
  out.max_w = max_w_;
  out.max_cell_rate = max_cell_rate_;
  out.steps = steps_;
  out.have_history = have_history_;
}

void FluidSolver::restore_state(const State& in) {
  vel_.u = in.vel.u;
  vel_.v = in.vel.v;
  vel_.w = in.vel.w;
  h_prev_->u = in.h_prev.u;
  h_prev_->v = in.h_prev.v;
  h_prev_->w = in.h_prev.w;
  p_ = in.p;
  time_ = in.time;
  dt_prev_ = in.dt_prev;
  kinetic_energy_ = in.kinetic_energy;
  nu_max_ = in.nu_max;
  max_u_ = in.max_u;
  max_v_ = in.max_v;
  max_w_ = in.max_w;
  max_cell_rate_ = in.max_cell_rate;
  steps_ = in.steps;
  have_history_ = in.have_history;
}

void FluidSolver::write_fields(const std::filesystem::path& h5_file, FieldSelection which) const {
  const grid::Grid& g = slabs_.grid();
  grid::CellField uc(slabs_), vc(slabs_), wc(slabs_), ox(slabs_), oy(slabs_), oz(slabs_);
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const Velocity& V = vel_;
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        uc(i, j, k) = 0.5 * (V.u(i, j, k) + V.u(i + 1, j, k)) * which.velocity_scale;
        vc(i, j, k) = 0.5 * (V.v(i, j, k) + V.v(i, j + 1, k)) * which.velocity_scale;
        wc(i, j, k) = 0.5 * (V.w(i, j, k) + V.w(i, j, k + 1)) * which.velocity_scale;
        // Central differences of the cell-centred interpolants (second order, one cell wide).
        auto ucx = [&](int a, int b, int c) { return 0.5 * (V.u(a, b, c) + V.u(a + 1, b, c)); };
        auto vcx = [&](int a, int b, int c) { return 0.5 * (V.v(a, b, c) + V.v(a, b + 1, c)); };
        auto wcx = [&](int a, int b, int c) { return 0.5 * (V.w(a, b, c) + V.w(a, b, c + 1)); };
        const double dwdy = 0.5 * (wcx(i, j + 1, k) - wcx(i, j - 1, k)) * idy;
        const double dvdz = 0.5 * (vcx(i, j, k + 1) - vcx(i, j, k - 1)) * idz;
        const double dudz = 0.5 * (ucx(i, j, k + 1) - ucx(i, j, k - 1)) * idz;
        const double dwdx = 0.5 * (wcx(i + 1, j, k) - wcx(i - 1, j, k)) * idx;
        const double dvdx = 0.5 * (vcx(i + 1, j, k) - vcx(i - 1, j, k)) * idx;
        const double dudy = 0.5 * (ucx(i, j + 1, k) - ucx(i, j - 1, k)) * idy;
        ox(i, j, k) = (dwdy - dvdz) * which.vorticity_scale;
        oy(i, j, k) = (dudz - dwdx) * which.vorticity_scale;
        oz(i, j, k) = (dvdx - dudy) * which.vorticity_scale;
      }
  {
    grid::FieldFile f(h5_file, slabs_, grid::FieldFile::Mode::create);
    f.set_compression(which.gzip_level);
    if (which.velocity) {
      f.write("velocity_x", uc);
      f.write("velocity_y", vc);
      f.write("velocity_z", wc);
    }
    if (which.pressure) {
      if (which.pressure_scale == 1) {
        f.write("pressure", p_);
      } else {
        grid::CellField ps(slabs_);
        for (int k = 0; k < p_.k_count(); ++k)
          for (int j = 0; j < g.ny(); ++j)
            for (int i = 0; i < g.nx(); ++i) ps(i, j, k) = p_(i, j, k) * which.pressure_scale;
        f.write("pressure", ps);
      }
    }
    if (which.vorticity) {
      f.write("vorticity_x", ox);
      f.write("vorticity_y", oy);
      f.write("vorticity_z", oz);
    }
    f.write_attribute("time", time_);
  }
  if (slabs_.rank() == 0 && which.write_xdmf) {
    auto xdmf = h5_file;
    xdmf.replace_extension(".xmf");
    std::vector<std::string> scalars;
    std::vector<grid::XdmfVector> vectors;
    if (which.pressure) scalars.push_back("pressure");
    if (which.velocity) vectors.push_back({"velocity", "velocity_x", "velocity_y", "velocity_z"});
    if (which.vorticity) vectors.push_back({"vorticity", "vorticity_x", "vorticity_y", "vorticity_z"});
    grid::write_xdmf(xdmf, h5_file.filename().string(), g, scalars, vectors, time_);
  }
}

}  // namespace systole::fluid
