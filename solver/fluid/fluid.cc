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
  if (!(p.viscous_safety > 0 && p.viscous_safety <= 1)) bad("viscous_safety", p.viscous_safety, "(0, 1]");
  if (!(p.darcy_permeability > 0 && std::isfinite(p.darcy_permeability)))
    bad("darcy_permeability", p.darcy_permeability, "(0, inf)");
  if (!(p.time_scale_s > 0)) bad("time_scale_s", p.time_scale_s, "(0, inf)");
  if (!(p.abort_cfl > 0)) bad("abort_cfl", p.abort_cfl, "(0, inf)");
  if (!(p.abort_energy_growth > 1)) bad("abort_energy_growth", p.abort_energy_growth, "(1, inf)");
  if (p.viscosity_model != "newtonian")
    throw InputError("fluid.viscosity_model = '" + p.viscosity_model +
                     "' is not available; known: newtonian (carreau_yasuda is not implemented yet)");
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
  apply_velocity_boundary_conditions(vel_);
}

FluidSolver::~FluidSolver() = default;

std::size_t FluidSolver::bytes_allocated() const {
  std::size_t fields = 3 * 3 + 3 + (force_ ? 3 : 0);
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

double FluidSolver::choose_time_step(double t_limit) const {
  const grid::Grid& g = slabs_.grid();
  double dt = par_.max_dt;
  if (par_.adaptive_dt) {
    const double rate = max_u_ / g.dx() + max_v_ / g.dy() + max_w_ / g.dz();
    if (rate > 0) dt = std::min(dt, par_.cfl / rate);
    const double nu = 1.0 / par_.reynolds;
    const double lam = 4 / (g.dx() * g.dx()) + 4 / (g.dy() * g.dy()) + 4 / (g.dz() * g.dz());
    dt = std::min(dt, par_.viscous_safety / (nu * lam));
  }
  // Land exactly on t_limit (round-off in t is absorbed); a leftover below ½Δt is avoided by
  // splitting the last 1.5Δt evenly (ours).
  const double remaining = t_limit - time_;
  if (dt >= remaining * (1 - 1e-9)) return remaining;
  if (remaining < 1.5 * dt) return 0.5 * remaining;
  return dt;
}

// ---- the explicit terms, eq 1–2: H = −∇·(u u) + Re⁻¹ ∇²u, at each velocity's own faces ----
void FluidSolver::compute_explicit_terms() {
  const grid::Grid& g = slabs_.grid();
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const double nu = 1 / par_.reynolds;
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
        hu[i] = lap - adv;
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
        hv[i] = lap - adv;
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
        hw[i] = lap - adv;
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
  double mu = 0, mv = 0, mw = 0, ke = 0, bad = 0;
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j) {
      const auto row = p_.index(0, j, k);
      const double *u = vel_.u.data() + row, *v = vel_.v.data() + row, *w = vel_.w.data() + row;
      for (int i = 0; i < g.nx(); ++i) {
        mu = std::max(mu, std::abs(u[i]));
        mv = std::max(mv, std::abs(v[i]));
        mw = std::max(mw, std::abs(w[i]));
        ke += u[i] * u[i] + v[i] * v[i] + w[i] * w[i];
      }
    }
  if (!std::isfinite(ke)) bad = 1;
  double local[4] = {mu, mv, mw, bad}, global[4];
  MPI_Allreduce(local, global, 4, MPI_DOUBLE, MPI_MAX, slabs_.comm());
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
    place << "step " << steps_ << " (max |u|,|v|,|w| = " << global[0] << ", " << global[1] << ", " << global[2] << ")";
    what << "realised CFL " << cfl << " > abort_cfl " << par_.abort_cfl << " with dt = " << dt;
    throw InstabilityError("fluid", place.str(), time_s, what.str());
  }
  if (dt > 0 && kinetic_energy_ > 0 && ke_new > par_.abort_energy_growth * kinetic_energy_) {
    std::ostringstream place, what;
    place << "step " << steps_ << " (max |u|,|v|,|w| = " << global[0] << ", " << global[1] << ", " << global[2] << ")";
    what << "kinetic energy grew by a factor " << ke_new / kinetic_energy_ << " > abort_energy_growth "
         << par_.abort_energy_growth << " in one step of dt = " << dt;
    throw InstabilityError("fluid", place.str(), time_s, what.str());
  }
  max_u_ = global[0];
  max_v_ = global[1];
  max_w_ = global[2];
  kinetic_energy_ = ke_new;
}

double FluidSolver::advance(double t_limit) {
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

void FluidSolver::write_fields(const std::filesystem::path& h5_file) const {
  const grid::Grid& g = slabs_.grid();
  grid::CellField uc(slabs_), vc(slabs_), wc(slabs_), ox(slabs_), oy(slabs_), oz(slabs_);
  const double idx = 1 / g.dx(), idy = 1 / g.dy(), idz = 1 / g.dz();
  const Velocity& V = vel_;
  for (int k = 0; k < p_.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        uc(i, j, k) = 0.5 * (V.u(i, j, k) + V.u(i + 1, j, k));
        vc(i, j, k) = 0.5 * (V.v(i, j, k) + V.v(i, j + 1, k));
        wc(i, j, k) = 0.5 * (V.w(i, j, k) + V.w(i, j, k + 1));
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
        ox(i, j, k) = dwdy - dvdz;
        oy(i, j, k) = dudz - dwdx;
        oz(i, j, k) = dvdx - dudy;
      }
  {
    grid::FieldFile f(h5_file, slabs_, grid::FieldFile::Mode::create);
    f.write("velocity_x", uc);
    f.write("velocity_y", vc);
    f.write("velocity_z", wc);
    f.write("pressure", p_);
    f.write("vorticity_x", ox);
    f.write("vorticity_y", oy);
    f.write("vorticity_z", oz);
    f.write_attribute("time", time_);
  }
  if (slabs_.rank() == 0) {
    auto xdmf = h5_file;
    xdmf.replace_extension(".xmf");
    grid::write_xdmf(xdmf, h5_file.filename().string(), g, {"pressure"},
                     {{"velocity", "velocity_x", "velocity_y", "velocity_z"},
                      {"vorticity", "vorticity_x", "vorticity_y", "vorticity_z"}},
                     time_);
  }
}

}  // namespace systole::fluid
