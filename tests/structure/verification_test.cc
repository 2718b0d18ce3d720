// Verification of solver/structure against derived or classical results:
// - the Fung law (eq 16-17) recovered from a flat sheet's measured tensions, with the seed's
//   alpha_f, alpha_c, along and across the fibre;
// - inflation of a closed spherical shell: the equilibrium radius of the continuum membrane
//   relation of this network, within 2 % and converging with refinement;
// - bending of a flat lattice into a cylinder: the discrete energy converges (order 2) to the
//   derived continuum limit;
// - energy conservation of the undamped integrator at the reported stable step and detection
//   of a run at twice that step.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "solver/core/errors.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"
#include "tests/structure/sphere_inflation.h"

namespace systole::structure {
namespace {

using geometry::Tissue;

constexpr double kAlphaF = 49.56, kAlphaC = 5.29;  // seed, §2.2
constexpr double kCLv = 13.3e-3;                    // kPa, seed LV

ShellMaterials seed_materials() {
  ShellMaterials m;
  for (auto& t : m.tissue) t = {kCLv, kAlphaF, kAlphaC};
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  return m;
}

// eq 17, written independently of the code under test.
double fung_tau(double eps, double alpha) { return kCLv * alpha * std::exp(alpha * eps * eps) * eps; }

// --- Fung sheet -------------------------------------------------------------------------------
// An equilateral sheet (edges along x at 0, 60, 120 degrees) stretched equibiaxially by lambda:
// every edge has eps = 1 - 1/lambda and interior nodes are in equilibrium. The nominal
// tensions measured through cuts (sum of the nodal forces on one side):
//   P_xx = (s / lambda) [tau_0 + tau_60 / 2],  P_yy = (3/2)(s / lambda) tau_60
// (virtual work on the lattice), so the stress of the x-edges is
//   tau_0 = (lambda / s) (P_xx - P_yy / 3),
// which must be eq 17 with alpha_f when the fibre is along x and alpha_c when it is along y.
struct SheetTensions {
  double pxx, pyy, interior_residual;
};
SheetTensions stretch_sheet(const Vec3& fibre, double lambda) {
  const int nx = 12, ny = 11;
  const double l = 1.0, s = 0.8;
  auto mesh = flat_sheet(nx, ny, l, s, Tissue::kLvMyocardium, fibre);
  ShellOptions opt;
  opt.bending = false;
  ShellModel body(mesh, seed_materials(), opt);
  std::vector<Vec3> x = mesh.position_mm;
  for (auto& p : x) p *= lambda;
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  const auto& f = body.forces_mn();
  const double xc = (nx / 2 - 0.25) * l, yc = (ny / 2 - 0.5) * l * std::sqrt(3.0) / 2;
  double fx = 0, fy = 0, residual = 0, fscale = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3& X = mesh.position_mm[i];
    if (X.x() < xc) fx += f[i].x();
    if (X.y() < yc) fy += f[i].y();
    fscale = std::max(fscale, f[i].norm());
    const bool boundary = X.x() < 0.6 * l || X.x() > (nx - 1.1) * l || X.y() < 0.1 || X.y() > (ny - 1.1) * l * std::sqrt(3.0) / 2;
    if (!boundary) residual = std::max(residual, f[i].norm());
  }
  const double height = (ny - 1) * l * std::sqrt(3.0) / 2;  // reference cut lengths
  const double width = (nx - 1) * l;                          // rows have nx - 1 edges (+ half at the shifted ends)
  (void)width;
  // Across a horizontal cut, each length l of cut carries two diagonal edges; the cut spans
  // nx - 1 + 1/2 cells in the shifted lattice: count them exactly as nodes per row minus 1/2.
  return {fx / height, fy / ((nx - 1) * l), residual / fscale};
}

TEST(StructureVerification, FungSheetReproducesFibreAndCrossFibreCurves) {
  const double s = 0.8;
  const double a60_fx = std::sqrt(kAlphaF * kAlphaF / 4 + 3 * kAlphaC * kAlphaC / 4);  // fibre along x
  double worst_f = 0, worst_c = 0;
  for (double eps : {0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3}) {
    const double lambda = 1 / (1 - eps);
    const SheetTensions along = stretch_sheet({1, 0, 0}, lambda);
    const SheetTensions across = stretch_sheet({0, 1, 0}, lambda);
    EXPECT_LT(along.interior_residual, 1e-12);
    // The derived lattice tensions.
    EXPECT_NEAR(along.pyy, 1.5 * s / lambda * fung_tau(eps, a60_fx), 1e-9 * along.pyy) << eps;
    const double tau_f = lambda / s * (along.pxx - along.pyy / 3);
    const double tau_c = lambda / s * (across.pxx - across.pyy / 3);
    worst_f = std::max(worst_f, std::abs(tau_f / fung_tau(eps, kAlphaF) - 1));
    worst_c = std::max(worst_c, std::abs(tau_c / fung_tau(eps, kAlphaC) - 1));
    std::cout << "  eps " << eps << ": fibre tau " << tau_f << " kPa (eq 17: " << fung_tau(eps, kAlphaF)
              << "), cross " << tau_c << " kPa (eq 17: " << fung_tau(eps, kAlphaC) << "); sheet P_xx/(s tau_f) "
              << along.pxx / (s * fung_tau(eps, kAlphaF)) << "\n";
  }
  EXPECT_LT(worst_f, 1e-9);
  EXPECT_LT(worst_c, 1e-9);
}

// --- Inflation ---------------------------------------------------------------------------------
// A closed shell under internal pressure p, scaled uniformly by lambda: every edge has
// eps = 1 - 1/lambda; virtual work (springs f = tau C / l, sum_e C_e = 3 s A0) gives the
// membrane tension T = 3 s tau / (2 lambda^2) and Laplace p = 2 T / (lambda R0):
//   p = 3 s tau(eps) / (lambda^3 R0).
double predicted_lambda(const SpringLaw& law, double p, double s, double r0, double alpha) {
  double lo = 1, hi = 1.6;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi);
    const double pm = 3 * s * law.stress(1 - 1 / mid, kCLv, alpha, LawParams{}) / (mid * mid * mid * r0);
    (pm < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double inflate(int level, const std::string& law, double p, double r0, double s) {
  ShellOptions opt;
  opt.law = law;
  opt.bending = false;  // the membrane relation (bending adds O((s/R)^2))
  return testing::inflate_to_rest(level, p, r0, s, seed_materials(), opt);
}

TEST(StructureVerification, InflatedSphereReachesTheMembraneRadius) {
  const double r0 = 10, s = 1;
  const double alpha_iso = std::sqrt((kAlphaF * kAlphaF + kAlphaC * kAlphaC) / 2);
  struct Case {
    std::string law;
    double p_kpa;
  };
  for (const Case& c : {Case{"linear", 0.0096}, Case{"fung", 0.02}}) {
    const double lam = predicted_lambda(find_spring_law(c.law), c.p_kpa, s, r0, alpha_iso);
    std::vector<double> err, lambdas;
    for (int level : {2, 3, 4, 5}) {
      const double measured = inflate(level, c.law, c.p_kpa, r0, s);
      lambdas.push_back(measured);
      err.push_back(std::abs(measured / lam - 1));
      std::cout << "  " << c.law << " level " << level << ": lambda " << measured << " (predicted " << lam
                << "), error " << err.back() << "\n";
    }
    EXPECT_GT(lam, 1.03) << c.law;  // a real inflation
    for (double e : err) EXPECT_LT(e, 0.02) << c.law;
    // Cauchy convergence of the measured radius: successive changes shrink by >= 3 per level
    // (order ~2 in the edge length).
    for (std::size_t k = 2; k < lambdas.size(); ++k)
      EXPECT_GT(std::abs(lambdas[k - 1] - lambdas[k - 2]) / std::abs(lambdas[k] - lambdas[k - 1]), 3.0)
          << c.law << " level " << k + 2;
  }
}

// --- Bending -----------------------------------------------------------------------------------
// A flat equilateral lattice (edge l, isotropic: no fibre) wrapped without stretching on a
// cylinder of radius R. For a quadratic height field z = x.K.x/2 the flat faces' slopes are
// those of the linear interpolant, so the hinge angles are exact lattice sums: bending across
// the x rows, theta = l/(2 sqrt3 R) for the x edges and l/(sqrt3 R) for the two diagonal
// families; summing k_b theta^2/2 over the three hinges of each pair of triangles (area
// sqrt(3)/2 l^2): W/A = sqrt(3) k_b / (4 R^2), i.e. kappa = sqrt(3) k_b / 2 (Seung & Nelson
// 1988, Phys. Rev. A 38:1005), which with the seed's k_b = 2B/sqrt(3) is the classical plate:
//   W/A = B / (2 R^2),  B = c alpha s^3 / [12 (1 - nu^2)].
// The cylinder is not exactly quadratic: the error is O((l/R)^2).
double cylinder_energy_density_error(double l_over_r, bool axis_along_y) {
  const double r = 10, l = l_over_r * r, s = 0.5;
  const int nx = 15, ny = 15;
  auto mesh = flat_sheet(nx, ny, l, s, Tissue::kLvMyocardium, Vec3::Zero());
  ShellModel body(mesh, seed_materials(), ShellOptions{});
  std::vector<Vec3> x = mesh.position_mm;
  for (auto& p : x) {
    const double u = axis_along_y ? p.x() : p.y(), phi = u / r;
    const double along = axis_along_y ? p.y() : p.x();
    p = axis_along_y ? Vec3(r * std::sin(phi), along, r * (1 - std::cos(phi)))
                     : Vec3(along, r * std::sin(phi), r * (1 - std::cos(phi)));
  }
  // Energy per family over the hinges (all hinges of a family are equivalent).
  double w[3] = {0, 0, 0};
  int n[3] = {0, 0, 0};
  for (const auto& h : body.hinges()) {
    const Vec3 d = mesh.position_mm[h.e1] - mesh.position_mm[h.e0];
    const int fam = std::abs(d.y()) < 1e-9 * l ? 0 : (d.x() * d.y() > 0 ? 1 : 2);
    // One hinge's energy through the code: a model of just this hinge is overkill; use the
    // total with every other hinge's contribution removed by symmetry instead: accumulate
    // k_b (1 - cos theta) from the public hinge data and check the total below.
    const Vec3 e = x[h.e1] - x[h.e0];
    const Vec3 n1 = e.cross(x[h.o1] - x[h.e0]);
    const Vec3 n2 = (x[h.e0] - x[h.e1]).cross(x[h.o2] - x[h.e1]);
    const double theta = std::atan2(n2.cross(n1).dot(e) / e.norm(), n1.dot(n2));
    w[fam] += h.kb_uj * (1 - std::cos(theta - h.theta0));
    ++n[fam];
  }
  double total = 0;
  for (int k = 0; k < 3; ++k) total += w[k];
  EXPECT_NEAR(total, body.bending_energy(x), 1e-12 * total);  // the sum is the code's energy
  const double density = (w[0] / n[0] + w[1] / n[1] + w[2] / n[2]) / (std::sqrt(3.0) / 2 * l * l);
  const double alpha = std::sqrt((kAlphaF * kAlphaF + kAlphaC * kAlphaC) / 2);  // no fibre: cos^2 = 1/2
  const double B = kCLv * alpha * s * s * s / (12 * (1 - 0.25));
  return density / (B / (2 * r * r)) - 1;
}

TEST(StructureVerification, CylindricalBendingConvergesToThePlateEnergy) {
  for (bool axis_y : {true, false}) {
    std::vector<double> h{0.2, 0.1, 0.05}, err;
    for (double lr : h) {
      err.push_back(std::abs(cylinder_energy_density_error(lr, axis_y)));
      std::cout << "  axis " << (axis_y ? "y" : "x") << ", l/R " << lr << ": relative error of W/A vs B/(2R^2) "
                << err.back() << "\n";
    }
    for (std::size_t k = 1; k < err.size(); ++k) {
      const double order = std::log(err[k - 1] / err[k]) / std::log(h[k - 1] / h[k]);
      std::cout << "  observed order " << order << "\n";
      EXPECT_GT(order, 1.9);
      EXPECT_LT(order, 2.1);
    }
    EXPECT_LT(err.back(), 1e-3);
  }
}

// A sphere that is flat at rest (theta0 = 0, ShellOptions::flat_rest_angles). Every face of a
// mesh inscribed in a sphere has its normal along the direction from the centre to its
// circumcentre (the foot of the perpendicular from the centre onto the face's plane), so the
// hinge angle is exactly the angle between the two faces' directions c1, c2 and
//   W = sum_hinges k_b (1 - c1_hat . c2_hat)
// (derived here; computed without the code's hinge angle). For an equilateral lattice every
// hinge turns by l/(sqrt(3) R), which gives W -> 4 pi k_b / sqrt(3) (= 8 pi kappa / 3 with the
// cylinder's kappa = sqrt(3) k_b / 2: the lattice's effective Gaussian modulus is -4 kappa / 3,
// derived, not cited); the icosphere is not equilateral and its limit is mesh-dependent
// (Schmidt & Fraternali 2012, J. Mech. Phys. Solids 60:172), measured a few % above.
TEST(StructureVerification, FlatAtRestSphereBendingEnergy) {
  ShellOptions opt;
  opt.flat_rest_angles = true;
  std::vector<double> ratio;
  for (int level = 1; level <= 5; ++level) {
    const auto mesh = icosphere(10, level, 1.0, Tissue::kLvMyocardium, false);
    ShellModel body(mesh, seed_materials(), opt);
    const auto& x = mesh.position_mm;
    double w_derived = 0;
    for (const BendingHinge& h : body.hinges()) {
      auto centre_dir = [&](std::int32_t a, std::int32_t b, std::int32_t c) {
        const Vec3 n = (x[b] - x[a]).cross(x[c] - x[a]).normalized();
        return (x[a].dot(n) * n).normalized();
      };
      w_derived += h.kb_uj * (1 - centre_dir(h.e0, h.e1, h.o1).dot(centre_dir(h.e1, h.e0, h.o2)));
    }
    const double w = body.bending_energy(x);
    EXPECT_NEAR(w / w_derived, 1, 1e-10) << "level " << level;
    const double lattice = 4 * M_PI * body.hinges().front().kb_uj / std::sqrt(3.0);
    ratio.push_back(w / lattice);
    std::cout << "  level " << level << " (" << mesh.node_count() << " nodes): W = " << w << " uJ, derived "
              << w_derived << ", W / (4 pi k_b / sqrt 3) = " << ratio.back() << "\n";
  }
  // Converging: successive changes shrink, to a limit within 5 % of the equilateral lattice's.
  for (std::size_t k = 3; k < ratio.size(); ++k)
    EXPECT_LT(std::abs(ratio[k] - ratio[k - 1]), std::abs(ratio[k - 1] - ratio[k - 2]));
  EXPECT_GT(ratio.back(), 1.0);
  EXPECT_LT(ratio.back(), 1.05);
}

// --- Integrator --------------------------------------------------------------------------------
ShellModel breathing_sphere() {
  ShellOptions opt;
  opt.law = "fung";
  ShellModel body(icosphere(10, 3, 1.0, Tissue::kLvMyocardium, true), seed_materials(), opt);
  std::vector<Vec3> x = body.positions_mm();
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-1e-3, 1e-3);
  // Released from rest at lambda = 1.12 about the pressurised equilibrium (lambda ~ 1.13):
  // the membrane stays in tension (a membrane in compression buckles, physically).
  for (auto& p : x) p = 1.12 * p + Vec3(u(rng), u(rng), u(rng));
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  body.set_cavity_pressure(0.02);
  return body;
}

// A pre-stretched Fung sheet (fibre along x, boundary pinned at lambda = 1.08) released from
// a smooth in-plane displacement (the lowest mode's shape): K + W_springs is the whole energy
// (in-plane motion stays in-plane: bending forces vanish by symmetry).
ShellModel vibrating_sheet() {
  const int nx = 21, ny = 19;
  auto mesh = flat_sheet(nx, ny, 1.0, 1.0, Tissue::kLvMyocardium, {1, 0, 0});
  ShellModel body(mesh, seed_materials(), ShellOptions{});
  std::vector<std::int32_t> edge;
  const double lx = nx - 0.5, ly = (ny - 1) * std::sqrt(3.0) / 2;
  std::vector<Vec3> x = mesh.position_mm;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3 X = mesh.position_mm[i];
    if (X.x() < 0.6 || X.x() > nx - 1.1 || X.y() < 0.1 || X.y() > ly - 0.1) edge.push_back(static_cast<std::int32_t>(i));
    x[i] = 1.08 * X + Vec3(0.05 * std::sin(M_PI * X.x() / lx) * std::sin(M_PI * X.y() / ly), 0, 0);
  }
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  for (auto i : edge) x[i] = 1.08 * mesh.position_mm[i];
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  body.fix_nodes(edge);
  return body;
}

TEST(StructureVerification, UndampedEnergyDriftBelowOneInAMillionPerPeriod) {
  // The reported stable step varies along the orbit (the Fung law stiffens with strain): a
  // first stretch of the orbit gives its smallest value, and the run then uses that fixed
  // step (velocity Verlet is symplectic only at a fixed step).
  double dt = 1e9, dt_max = 0;
  {
    ShellModel probe = vibrating_sheet();
    while (probe.time_ms() < 100) {
      const double d = probe.stable_step_ms();
      dt = std::min(dt, d);
      dt_max = std::max(dt_max, d);
      probe.substep(d);
    }
  }
  ShellModel body = vibrating_sheet();
  std::vector<double> t, e, probe_x;
  const double e0 = body.energies().total_uj();
  const std::size_t centre = body.node_count() / 2;
  for (int k = 0; k < 4000; ++k) {
    body.substep(dt);
    t.push_back(body.time_ms());
    e.push_back(body.energies().total_uj());
    probe_x.push_back(body.positions_mm()[centre].x());
  }
  // Period of the centre node's x motion (mean crossings).
  double mean = 0;
  for (double v : probe_x) mean += v / probe_x.size();
  std::vector<double> up;
  for (std::size_t k = 1; k < probe_x.size(); ++k)
    if (probe_x[k - 1] < mean && probe_x[k] >= mean) up.push_back(t[k]);
  ASSERT_GE(up.size(), 10u);
  const double period = (up.back() - up.front()) / (up.size() - 1);
  // Drift: least-squares slope through the energy averaged over each whole period (the
  // averaging removes the bounded oscillation of the Verlet energy error).
  std::vector<double> tp, ep;
  double fluct = 0;
  for (std::size_t k = 0; k < e.size(); ++k) fluct = std::max(fluct, std::abs(e[k] - e0) / e0);
  for (std::size_t w = 0; w + 1 < up.size(); ++w) {
    double sum = 0;
    int n = 0;
    for (std::size_t k = 0; k < t.size(); ++k)
      if (t[k] >= up[w] && t[k] < up[w + 1]) sum += e[k], ++n;
    tp.push_back(0.5 * (up[w] + up[w + 1]));
    ep.push_back(sum / n);
  }
  double tm = 0, em = 0;
  for (std::size_t k = 0; k < tp.size(); ++k) tm += tp[k] / tp.size(), em += ep[k] / ep.size();
  double num = 0, den = 0;
  for (std::size_t k = 0; k < tp.size(); ++k) {
    num += (tp[k] - tm) * (ep[k] - em);
    den += (tp[k] - tm) * (tp[k] - tm);
  }
  const double drift = std::abs(num / den) * period / e0;
  std::cout << "  4000 substeps at dt " << dt << " ms (reported steps on the orbit " << dt << " to " << dt_max
            << " ms), period " << period << " ms (" << up.size() - 1 << " periods), drift per period " << drift
            << "; largest |E - E0| / E0 " << fluct << "\n";
  EXPECT_LT(drift, 1e-6);
  EXPECT_LT(fluct, 1e-2);
}

TEST(StructureVerification, TwiceTheReportedStepIsDetectedAsUnstable) {
  ShellModel body = breathing_sphere();
  int steps = 0;
  try {
    for (; steps < 5000; ++steps) body.substep(2 * body.stable_step_ms());
    FAIL() << "2 x the reported step ran 5000 substeps without a diagnosis";
  } catch (const InstabilityError& err) {
    const std::string what = err.what();
    std::cout << "  detected after " << steps << " substeps: " << what << "\n";
    EXPECT_EQ(err.module(), "structure");
    EXPECT_NE(what.find("body 'sphere' node"), std::string::npos);
    EXPECT_GT(err.time_s(), 0);
  }
  // The same run at the reported step (re-estimated every substep) stays bounded.
  ShellModel stable = breathing_sphere();
  double ke_first = 0, ke_last = 0;
  for (int k = 0; k < 2000; ++k) {
    stable.substep(stable.stable_step_ms());
    if (k < 500) ke_first = std::max(ke_first, stable.energies().kinetic_uj);
    if (k >= 1500) ke_last = std::max(ke_last, stable.energies().kinetic_uj);
  }
  std::cout << "  peak kinetic energy in the first / last 500 substeps " << ke_first << " / " << ke_last << " uJ\n";
  EXPECT_LT(ke_last, 1.5 * ke_first);  // bounded (energy moves between modes, it does not grow)
  std::cout << "  2000 substeps at the reported step: t = " << stable.time_ms() << " ms, max |strain| "
            << stable.max_abs_strain() << "\n";
  EXPECT_LT(stable.max_abs_strain(), 0.4);
}

}  // namespace
}  // namespace systole::structure
