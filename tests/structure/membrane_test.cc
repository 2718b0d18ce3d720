// The constant-strain Fung membrane triangles (ShellOptions::membrane = "triangles"):
// - forces are minus the gradient of the energy (central differences) and free of net force and
//   torque;
// - the patch test: on an irregular sheet under any affine map, every interior node is in
//   equilibrium and the energy is the exact s A (c/2)(e^Q - 1) of that strain;
// - the fibre frame: stretches along and across the fibre give eq 16's energy with eq 17's
//   strain eps = 1 - 1/lambda and alpha_f, alpha_c; a simple shear in the fibre frame adds the
//   shear term alpha_c gamma^2 / 2;
// - a closed isotropic sphere inflated to rest against the derived membrane relation
//   p = 2 s c alpha eps e^Q / (R0 lambda^4), eps = 1 - 1/lambda, Q = 2 alpha eps^2, converging
//   with refinement;
// - an open cylinder with axial fibres stretched uniformly against the derived anisotropic
//   membrane pressure (the hoop is the cross-fibre direction), converging with refinement.
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
constexpr double kAlphaF = 49.56, kAlphaC = 5.29;  // seed, eq 16
constexpr double kC = 13.3e-3;                     // kPa, the seed's LV c

ShellMaterials seed_materials() {
  ShellMaterials m;
  for (auto& t : m.tissue) t = {kC, kAlphaF, kAlphaC};
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  return m;
}

ShellOptions membrane_options() {
  ShellOptions o;
  o.membrane = "triangles";
  o.bending = false;
  return o;
}

// A flat sheet with fibres at 30 deg whose interior nodes are moved in-plane by up to 0.25 edge
// (an irregular mesh).
geometry::TriMesh irregular_sheet(int nx, int ny, unsigned seed) {
  auto mesh = flat_sheet(nx, ny, 1.0, 0.8, Tissue::kLvMyocardium, Vec3(std::cos(0.5236), std::sin(0.5236), 0));
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-0.25, 0.25);
  const double xmax = nx - 0.5, ymax = (ny - 1) * std::sqrt(3.0) / 2;
  for (auto& p : mesh.position_mm)
    if (p.x() > 0.6 && p.x() < xmax - 1.1 && p.y() > 0.1 && p.y() < ymax - 0.1) p += Vec3(u(rng), u(rng), 0);
  return mesh;
}

TEST(Membrane, ForcesAreMinusTheEnergyGradientAndFreeOfNetForceAndTorque) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (const bool sphere : {true, false}) {
    const auto mesh = sphere ? icosphere(10, 2, 1.0, Tissue::kLvMyocardium, true) : irregular_sheet(7, 6, 3);
    ShellModel body(mesh, seed_materials(), membrane_options());
    std::vector<Vec3> x = mesh.position_mm;
    for (auto& p : x) p = 1.15 * p + Vec3(u(rng), u(rng), u(rng));  // stretched and perturbed
    std::vector<Vec3> f(x.size(), Vec3::Zero());
    body.add_membrane_forces(x, f);
    double err = 0, fmax = 0;
    Vec3 net = Vec3::Zero(), torque = Vec3::Zero();
    const double h = 1e-6;
    for (std::size_t i = 0; i < x.size(); ++i) {
      net += f[i];
      torque += x[i].cross(f[i]);
      fmax = std::max(fmax, f[i].norm());
      for (int d = 0; d < 3; ++d) {
        std::vector<Vec3> xp = x, xm = x;
        xp[i][d] += h;
        xm[i][d] -= h;
        const double grad = (body.membrane_energy(xp) - body.membrane_energy(xm)) / (2 * h);
        err = std::max(err, std::abs(f[i][d] + grad));
      }
    }
    std::cout << "  " << (sphere ? "sphere" : "sheet") << ": max |F + dW/dx| / max |F| = " << err / fmax << "\n";
    EXPECT_GT(fmax, 0);
    EXPECT_LT(err / fmax, 1e-6) << (sphere ? "sphere" : "sheet");
    EXPECT_LT(net.norm() / fmax, 1e-12);
    EXPECT_LT(torque.norm() / (fmax * 20), 1e-12);
  }
}

// The energy density of the deformed fibre and cross-fibre vectors a = F f0, b = F c0 by eq 16
// with eq 17's strain and the shear term, written apart from the code under test.
double fung_energy_density(const Vec3& a, const Vec3& b) {
  const double ef = 1 - 1 / a.norm(), ec = 1 - 1 / b.norm(), gamma = a.dot(b) / a.cross(b).norm();
  const double q = kAlphaF * ef * ef + kAlphaC * ec * ec + 0.5 * kAlphaC * gamma * gamma;
  return 0.5 * kC * std::expm1(q);
}

TEST(Membrane, PatchTestOnAnIrregularSheet) {
  const auto mesh = irregular_sheet(12, 11, 11);
  ShellModel body(mesh, seed_materials(), membrane_options());
  // An affine map with stretch, shear, rotation and a lift out of the plane.
  Eigen::Matrix3d A;
  A << 1.12, 0.07, 0.0, -0.04, 0.93, 0.0, 0.05, 0.10, 1.0;
  std::vector<Vec3> x = mesh.position_mm;
  for (auto& p : x) p = A * p + Vec3(0.3, -0.2, 0.5);
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  const auto& f = body.forces_mn();
  double interior = 0, fmax = 0;
  const double xmax = 11.5, ymax = 10 * std::sqrt(3.0) / 2;
  for (std::size_t i = 0; i < x.size(); ++i) {
    fmax = std::max(fmax, f[i].norm());
    const Vec3& X = mesh.position_mm[i];
    const bool boundary = X.x() < 0.6 || X.x() > xmax - 1.1 || X.y() < 0.1 || X.y() > ymax - 0.1;
    if (!boundary) interior = std::max(interior, f[i].norm());
  }
  // The exact energy: E in the fibre frame (f0 at 30 deg, c0 = z x f0) of F = A restricted to the plane.
  const Vec3 f0(std::cos(0.5236), std::sin(0.5236), 0), c0 = Vec3::UnitZ().cross(f0);
  double area = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) area += mesh.area_mm2(t);
  const double exact = 0.8 * area * fung_energy_density(A * f0, A * c0);
  const double w = body.membrane_energy(x);
  std::cout << "  interior residual / max force " << interior / fmax << ", energy " << w << " uJ (exact " << exact
            << ")\n";
  EXPECT_LT(interior / fmax, 1e-10);
  EXPECT_NEAR(w, exact, 1e-10 * exact);
}

// One triangle stretched along and across its fibre and sheared in the fibre frame.
TEST(Membrane, FibreFrameGivesEq16AlongAndAcrossTheFibre) {
  auto mesh = flat_sheet(3, 3, 1.0, 1.0, Tissue::kLvMyocardium, Vec3(1, 1, 0));  // fibre at 45 deg
  ShellModel body(mesh, seed_materials(), membrane_options());
  const Vec3 f0 = Vec3(1, 1, 0).normalized(), c0 = Vec3::UnitZ().cross(f0);
  double area = 0;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) area += mesh.area_mm2(t);
  for (const double lam : {0.8, 1.05, 1.15, 1.25}) {
    const Eigen::Matrix3d along = Eigen::Matrix3d::Identity() + (lam - 1) * f0 * f0.transpose();
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() + (lam - 1) * c0 * c0.transpose();
    const double g = lam - 1;  // simple shear x = X + g (X . c0) f0: a = f0, b = c0 + g f0, gamma = g
    const Eigen::Matrix3d shear = Eigen::Matrix3d::Identity() + g * f0 * c0.transpose();
    const double e = 1 - 1 / lam, eg = 1 - 1 / std::sqrt(1 + g * g);
    const double expected[3] = {0.5 * kC * std::expm1(kAlphaF * e * e), 0.5 * kC * std::expm1(kAlphaC * e * e),
                                0.5 * kC * std::expm1(kAlphaC * eg * eg + 0.5 * kAlphaC * g * g)};
    int k = 0;
    for (const Eigen::Matrix3d& F : {along, across, shear}) {
      std::vector<Vec3> x = mesh.position_mm;
      for (auto& p : x) p = F * p;
      EXPECT_NEAR(body.membrane_energy(x), area * expected[k], 1e-11 * area * expected[k]) << "lambda " << lam << " case " << k;
      ++k;
    }
  }
}

// Isotropic sphere (no fibre: alpha = sqrt((alpha_f^2 + alpha_c^2)/2) in both directions)
// inflated to rest; the derived radius from virtual work on the continuum membrane.
double predicted_lambda(double p, double s, double r0, double alpha) {
  double lo = 1, hi = 1.6;
  for (int k = 0; k < 200; ++k) {
    const double mid = 0.5 * (lo + hi), e = 1 - 1 / mid;
    const double pm = 2 * s * kC * alpha * e * std::exp(2 * alpha * e * e) / (r0 * mid * mid * mid * mid);
    (pm < p ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double inflate(int level, double p, double r0, double s) {
  return testing::inflate_to_rest(level, p, r0, s, seed_materials(), membrane_options());
}

TEST(Membrane, InflatedIsotropicSphereReachesTheMembraneRadius) {
  const double r0 = 10, s = 1, p = 0.02;
  const double alpha = std::sqrt((kAlphaF * kAlphaF + kAlphaC * kAlphaC) / 2);
  const double lam = predicted_lambda(p, s, r0, alpha);
  std::vector<double> err;
  for (int level : {2, 3, 4}) {
    const double measured = inflate(level, p, r0, s);
    err.push_back(std::abs(measured / lam - 1));
    std::cout << "  level " << level << ": lambda " << measured << " (predicted " << lam << "), error " << err.back()
              << "\n";
  }
  EXPECT_GT(lam, 1.03);  // a real inflation
  EXPECT_LT(err.back(), 2e-3);
  for (std::size_t k = 1; k < err.size(); ++k) {
    const double order = std::log2(err[k - 1] / err[k]);
    std::cout << "  observed order " << order << "\n";
    EXPECT_GT(order, 1.5) << "level " << k + 2;
  }
}

// A cylinder (radius R, axis y, fibres along the axis) stretched uniformly, hoop by lt and axially
// by lz: every triangle's fibre and cross-fibre stretches are exactly lz and lt, so the membrane
// is in equilibrium with the internal pressure of virtual work on the continuum,
//   p = dw/dlt / (lt lz R) = s c e^Q alpha_c eps_t / (lt^3 lz R),  Q = alpha_f eps_z^2 + alpha_c eps_t^2,
// the anisotropic relation (the hoop is the cross-fibre direction). Measured: the largest residual
// |F_int + p a_i| / |p a_i| over the interior nodes of a 90-degree sector (a_i the node's share of
// the outward area vector); the chords' faceting makes it O((l/R)^2).
double cylinder_residual(double edge_mm) {
  const double r = 10, lt = 1.08, lz = 1.04, s = 0.8;
  const int nx = static_cast<int>(std::lround(0.5 * M_PI * r / edge_mm)) + 1;
  const int ny = static_cast<int>(std::lround(6.0 / (edge_mm * std::sqrt(3.0) / 2))) + 1;
  auto mesh = flat_sheet(nx, ny, edge_mm, s, Tissue::kLvMyocardium, Vec3::UnitY());
  for (auto& p : mesh.position_mm) p = Vec3(r * std::sin(p.x() / r), p.y(), r * std::cos(p.x() / r));
  ShellModel body(mesh, seed_materials(), membrane_options());
  std::vector<Vec3> x = mesh.position_mm;
  for (auto& p : x) p = Vec3(lt * p.x(), lz * p.y(), lt * p.z());
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  const double et = 1 - 1 / lt, ez = 1 - 1 / lz;
  const double p_kpa = s * kC * std::exp(kAlphaF * ez * ez + kAlphaC * et * et) * kAlphaC * et / (lt * lt * lt * lz * r);
  std::vector<Vec3> area(x.size(), Vec3::Zero());  // outward (+z at the sector's middle) area shares
  for (const auto& t : mesh.tri) {
    const Vec3 an = 0.5 * (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    for (int k = 0; k < 3; ++k) area[t[k]] += an / 3;
  }
  const double xmax = (nx - 0.5) * edge_mm, ymax = (ny - 1) * edge_mm * std::sqrt(3.0) / 2;
  double worst = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double arc = r * std::atan2(mesh.position_mm[i].x(), mesh.position_mm[i].z()), y = mesh.position_mm[i].y();
    if (arc < 1.1 * edge_mm || arc > xmax - 1.6 * edge_mm || y < 0.1 * edge_mm || y > ymax - 0.1 * edge_mm) continue;
    const Vec3 load = p_kpa * area[i];
    worst = std::max(worst, (body.forces_mn()[i] + load).norm() / load.norm());
  }
  return worst;
}

TEST(Membrane, StretchedCylinderBalancesTheAnisotropicMembranePressure) {
  std::vector<double> err;
  for (double edge : {1.0, 0.5, 0.25}) {
    err.push_back(cylinder_residual(edge));
    std::cout << "  edge " << edge << " mm: largest interior residual " << err.back() << " of the pressure load\n";
  }
  EXPECT_LT(err.back(), 2e-3);
  for (std::size_t k = 1; k < err.size(); ++k) {
    const double order = std::log2(err[k - 1] / err[k]);
    std::cout << "  observed order " << order << "\n";
    EXPECT_GT(order, 1.5);
  }
}

TEST(Membrane, RefusesALawOtherThanFungAndAnUnknownModel) {
  ShellOptions o = membrane_options();
  o.law = "linear";
  EXPECT_THROW(ShellModel(icosphere(10, 1, 1, Tissue::kLvMyocardium, false), seed_materials(), o), InputError);
  o = membrane_options();
  o.membrane = "quads";
  EXPECT_THROW(ShellModel(icosphere(10, 1, 1, Tissue::kLvMyocardium, false), seed_materials(), o), InputError);
}

}  // namespace
}  // namespace systole::structure
