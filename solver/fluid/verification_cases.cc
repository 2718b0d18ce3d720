#include "solver/fluid/verification_cases.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <memory>
#include <vector>
#include <numbers>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/fluid/fluid.h"
#include "solver/fluid/operators.h"

namespace systole::fluid {

namespace {
constexpr double kPi = std::numbers::pi;
struct CaseNames {
  VerificationCase c;
  const char* name;
};
constexpr CaseNames kCases[] = {{VerificationCase::taylor_green_2d, "taylor_green_2d"},
                                {VerificationCase::poiseuille, "poiseuille"},
                                {VerificationCase::couette, "couette"},
                                {VerificationCase::womersley, "womersley"},
                                {VerificationCase::taylor_green_3d, "taylor_green_3d"}};

// The exact solution of a case (u, v at their faces), where there is one.
struct Exact {
  std::function<double(double, double, double, double)> u, v;  // (x, y, z, t)
  double peak = 1;                                             // peak velocity magnitude
};

grid::BoxSpec box_for(const FluidCaseSpec& s) {
  switch (s.case_name) {
    case VerificationCase::taylor_green_2d:
      return {s.nx, s.ny, s.nz, 2 * kPi, 2 * kPi, 2 * kPi * s.nz / s.nx};
    case VerificationCase::poiseuille:
    case VerificationCase::couette: return {s.nx, s.ny, s.nz, 1, 1, 1};
    case VerificationCase::womersley: return {s.nx, s.ny, s.nz, 1, 1, 2};
    case VerificationCase::taylor_green_3d: return {s.nx, s.ny, s.nz, 2 * kPi, 2 * kPi, kPi};
  }
  return {};
}

// Womersley: u_t = cos(ωt) + Re⁻¹ u_zz on 0 < z < 2, u = 0 at the walls.
// u = Re[ U(z) e^{iωt} ], U = (1/(iω)) (1 − cosh(λ(z−1))/cosh λ), λ = √(iωRe).
std::complex<double> womersley_profile(double z, double omega, double re) {
  using C = std::complex<double>;
  const C i(0, 1);
  const C lambda = std::sqrt(i * omega * re);
  return (1.0 / (i * omega)) * (1.0 - std::cosh(lambda * (z - 1.0)) / std::cosh(lambda));
}

struct Errors {
  double l2 = 0, linf = 0;
};
Errors velocity_errors(const FluidSolver& f, const Exact& e, double t) {
  const grid::Slabs& s = f.slabs();
  const grid::Grid& g = s.grid();
  using grid::Location;
  double sum = 0, mx = 0;
  const Velocity& V = f.velocity();
  for (int k = 0; k < V.u.k_count(); ++k) {
    const int kg = s.k_begin() + k;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        const double eu = V.u(i, j, k) - e.u(g.x(Location::x_face, i), g.y(Location::x_face, j), g.z(Location::x_face, kg), t);
        const double ev = V.v(i, j, k) - e.v(g.x(Location::y_face, i), g.y(Location::y_face, j), g.z(Location::y_face, kg), t);
        const double ew = V.w(i, j, k);
        sum += eu * eu + ev * ev + ew * ew;
        mx = std::max({mx, std::abs(eu), std::abs(ev), std::abs(ew)});
      }
  }
  double in[1] = {sum}, out[1];
  MPI_Allreduce(in, out, 1, MPI_DOUBLE, MPI_SUM, s.comm());
  double gmx = 0;
  MPI_Allreduce(&mx, &gmx, 1, MPI_DOUBLE, MPI_MAX, s.comm());
  return {std::sqrt(out[0] / (2.0 * static_cast<double>(g.cells()))) / e.peak, gmx / e.peak};
}
}  // namespace

const char* to_string(VerificationCase c) {
  for (const auto& n : kCases)
    if (n.c == c) return n.name;
  return "?";
}

VerificationCase parse_verification_case(const std::string& name) {
  std::string known;
  for (const auto& n : kCases) {
    if (name == n.name) return n.c;
    known += (known.empty() ? "" : ", ") + std::string(n.name);
  }
  throw InputError("fluid.verification_case = '" + name + "' is unknown; known: " + known);
}

RunResult run_verification_case(const FluidCaseSpec& spec, MPI_Comm comm,
                                const std::function<void(const ProgressReport&)>& progress,
                                const std::function<bool()>& cancel) {
  if (!(spec.end_time > 0)) throw InputError("fluid.end_time = " + std::to_string(spec.end_time) + " must be > 0");
  if (spec.samples < 1 || spec.samples > 100000)
    throw InputError("fluid.samples = " + std::to_string(spec.samples) + " is out of range [1, 100000]");
  if (spec.case_name == VerificationCase::womersley && !(spec.womersley_number > 0 && spec.womersley_number <= 100))
    throw InputError("fluid.womersley_number = " + std::to_string(spec.womersley_number) + " is out of range (0, 100]");
  const bool shear_thinning = spec.viscosity_model == "carreau_yasuda";
  if (shear_thinning && spec.case_name != VerificationCase::poiseuille && spec.case_name != VerificationCase::couette)
    throw InputError(std::string("fluid.viscosity_model = 'carreau_yasuda' needs a case with a reference solution for it: "
                                 "fluid.verification_case = poiseuille or couette, not ") +
                     to_string(spec.case_name));
  const grid::Grid grid(box_for(spec));
  const grid::Slabs slabs(grid, comm);

  FluidParameters par;
  par.reynolds = spec.reynolds;
  par.cfl = spec.cfl;
  par.max_dt = spec.max_dt;
  par.adaptive_dt = spec.adaptive_dt;
  par.time_scale_s = spec.time_scale_s;
  par.viscosity_model = spec.viscosity_model;
  par.carreau_yasuda = spec.carreau_yasuda;
  par.subgrid_model = spec.subgrid_model;
  par.subgrid_constant = spec.subgrid_constant;
  par.darcy_regions.clear();
  const double re = spec.reynolds;
  Exact exact;
  std::function<double(double, double, double)> u0, v0, w0 = [](double, double, double) { return 0.0; };
  double omega = 0;
  switch (spec.case_name) {
    case VerificationCase::taylor_green_2d:
      par.bottom_wall.kind = par.top_wall.kind = WallKind::free_slip;
      exact.u = [re](double x, double y, double, double t) { return std::sin(x) * std::cos(y) * std::exp(-2 * t / re); };
      exact.v = [re](double x, double y, double, double t) { return -std::cos(x) * std::sin(y) * std::exp(-2 * t / re); };
      exact.peak = 1;
      break;
    case VerificationCase::taylor_green_3d:
      par.bottom_wall.kind = par.top_wall.kind = WallKind::free_slip;
      u0 = [](double x, double y, double z) { return std::sin(x) * std::cos(y) * std::cos(z); };
      v0 = [](double x, double y, double z) { return -std::cos(x) * std::sin(y) * std::cos(z); };
      break;
    case VerificationCase::poiseuille:
      if (shear_thinning) {
        // The 1-D reference at the z levels of the x-faces (cell centres), computed once.
        const CarreauYasuda law = spec.carreau_yasuda;
        auto profile = std::make_shared<std::vector<double>>(grid.nz());
        double peak = 0;
        for (int k = 0; k < grid.nz(); ++k) {
          (*profile)[k] = plane_poiseuille_velocity(law, 8.0 / re, 1.0, grid.z(grid::Location::x_face, k));
          peak = std::max(peak, (*profile)[k]);
        }
        const double dz = grid.dz();
        exact.u = [profile, dz](double, double, double z, double) {
          return (*profile)[static_cast<std::size_t>(std::lround(z / dz - 0.5))];
        };
        exact.peak = std::max(peak, plane_poiseuille_velocity(law, 8.0 / re, 1.0, 0.5));
      } else {
        exact.u = [](double, double, double z, double) { return 4 * z * (1 - z); };
      }
      exact.v = [](double, double, double, double) { return 0.0; };
      u0 = v0 = [](double, double, double) { return 0.0; };
      break;
    case VerificationCase::couette:
      par.top_wall.velocity_x = 1;
      exact.u = [](double, double, double z, double) { return z; };
      exact.v = [](double, double, double, double) { return 0.0; };
      u0 = v0 = [](double, double, double) { return 0.0; };
      break;
    case VerificationCase::womersley: {
      omega = spec.womersley_number * spec.womersley_number / re;  // half-width Lz/2 = 1
      exact.u = [omega, re](double, double, double z, double t) {
        return std::real(womersley_profile(z, omega, re) * std::exp(std::complex<double>(0, omega * t)));
      };
      exact.v = [](double, double, double, double) { return 0.0; };
      double peak = 0;
      for (int a = 0; a < 64; ++a)
        for (int b = 0; b <= 200; ++b)
          peak = std::max(peak, std::abs(exact.u(0, 0, 2.0 * b / 200, 2 * kPi * a / (64 * omega))));
      exact.peak = peak;
      break;
    }
  }
  if (exact.u) {
    u0 = [&exact](double x, double y, double z) { return exact.u(x, y, z, 0); };
    v0 = [&exact](double x, double y, double z) { return exact.v(x, y, z, 0); };
  }

  FluidSolver fluid(slabs, par);
  if (spec.case_name == VerificationCase::poiseuille) {
    const double g = 8.0 / re;
    fluid.set_body_force([g](const StepContext&, const Velocity&, Velocity& f) { f.u.fill(g); });
  } else if (spec.case_name == VerificationCase::womersley) {
    fluid.set_body_force([omega](const StepContext& c, const Velocity&, Velocity& f) {
      f.u.fill(std::cos(omega * (c.time + 0.5 * c.dt)));  // midpoint: second order (eq 8)
    });
  }
  fluid.set_velocity(u0, v0, w0);

  RunResult result;
  Series time_s{"time_s", "s", {}}, ke{"kinetic_energy", "", {}}, diss{"dissipation", "", {}},
      divs{"max_divergence", "", {}};
  double max_div_all = 0, womersley_max_error = 0, energy_integral = 0;
  auto sample = [&] {
    const FlowDiagnostics d = fluid.diagnostics();
    time_s.values.push_back(fluid.time() * spec.time_scale_s);
    ke.values.push_back(d.kinetic_energy);
    diss.values.push_back(d.dissipation);
    divs.values.push_back(d.max_divergence);
    if (spec.case_name == VerificationCase::womersley)
      womersley_max_error = std::max(womersley_max_error, velocity_errors(fluid, exact, fluid.time()).linf);
  };
  sample();
  const double e0 = fluid.diagnostics().kinetic_energy;
  double eps_prev = fluid.diagnostics().dissipation;
  bool cancelled = false;
  for (int n = 1; n <= spec.samples && !cancelled; ++n) {
    const double t_sample = spec.end_time * n / spec.samples;
    while (fluid.time() < t_sample * (1 - 1e-14)) {
      const double dt = fluid.advance(t_sample);
      const grid::Grid& g = slabs.grid();
      double local = max_abs_divergence_local(g, fluid.velocity().u, fluid.velocity().v, fluid.velocity().w), div = 0;
      MPI_Allreduce(&local, &div, 1, MPI_DOUBLE, MPI_MAX, slabs.comm());
      max_div_all = std::max(max_div_all, div);
      if (spec.case_name == VerificationCase::taylor_green_3d) {
        const double eps = fluid.diagnostics().dissipation;
        energy_integral += 0.5 * dt * (eps + eps_prev);
        eps_prev = eps;
      }
    }
    sample();
    if (progress) {
      ProgressReport r;
      r.simulated_time_s = fluid.time() * spec.time_scale_s;
      r.fraction = static_cast<double>(n) / spec.samples;
      r.message = std::string("fluid ") + to_string(spec.case_name) + ": step " + std::to_string(fluid.steps());
      progress(r);
    }
    if (cancel) {
      int local = cancel() ? 1 : 0, any = 0;
      MPI_Allreduce(&local, &any, 1, MPI_INT, MPI_MAX, slabs.comm());
      cancelled = any != 0;
    }
  }

  auto& m = result.metrics;
  const FlowDiagnostics d = fluid.diagnostics();
  if (exact.u) {
    const Errors e = velocity_errors(fluid, exact, fluid.time());
    m["error_l2_relative"] = e.l2;
    m["error_linf_relative"] = e.linf;
  }
  if (spec.case_name == VerificationCase::poiseuille || spec.case_name == VerificationCase::couette)
    m["reference_peak_velocity"] = exact.peak;
  m["max_viscosity"] = fluid.max_viscosity();
  if (spec.case_name == VerificationCase::womersley) {
    m["error_linf_max_over_samples_relative"] = womersley_max_error;
    m["womersley_number"] = spec.womersley_number;
    m["womersley_peak_velocity"] = exact.peak;
  }
  if (spec.case_name == VerificationCase::taylor_green_3d)
    m["energy_balance_relative_error"] = std::abs(d.kinetic_energy - e0 + energy_integral) / e0;
  const std::vector<double> flux = fluid.volume_flux_x();
  const auto [lo, hi] = std::minmax_element(flux.begin(), flux.end());
  // Relative to the flux of the velocity scale (1) through the whole cross-section.
  m["mass_flux_relative_variation"] = (*hi - *lo) / (grid.ly() * grid.lz() * exact.peak);
  m["max_divergence_all_steps"] = max_div_all;
  m["max_divergence_final"] = d.max_divergence;
  m["kinetic_energy_final"] = d.kinetic_energy;
  m["dissipation_final"] = d.dissipation;
  m["steps"] = static_cast<double>(fluid.steps());
  m["end_time"] = fluid.time();
  m["last_dt"] = fluid.last_dt();
  m["reynolds"] = re;
  m["poisson_self_test_relative_divergence"] = fluid.poisson().self_test_relative_divergence();
  m["cells"] = static_cast<double>(grid.cells());
  m["ranks"] = slabs.size();
  m["cancelled"] = cancelled ? 1 : 0;
  result.series = {time_s, ke, diss, divs};
  for (const auto& w : fluid.warnings()) result.notes.push_back(w);
  result.notes.push_back(std::string("fluid verification case ") + to_string(spec.case_name));
  m["fields_written"] = 0;
  if (!spec.output_dir.empty()) {
    if (slabs.rank() == 0) std::filesystem::create_directories(spec.output_dir);
    MPI_Barrier(slabs.comm());
    fluid.write_fields(spec.output_dir / "fluid_fields.h5",
                       {spec.write_velocity, spec.write_pressure, spec.write_vorticity});
    m["fields_written"] = 1;
  }
  return result;
}

}  // namespace systole::fluid
