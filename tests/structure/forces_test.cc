// Forces are minus the gradient of the energies (central finite differences on randomly
// perturbed meshes), internal forces carry no net force or torque, and bad input is rejected
// with messages naming what is wrong.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>
#include <random>

#include "solver/core/errors.h"
#include "solver/structure/shapes.h"
#include "solver/structure/shell.h"

namespace systole::structure {
namespace {

using geometry::Tissue;

ShellMaterials seed_materials() {
  ShellMaterials m;
  for (auto& t : m.tissue) t = {13.3e-3, 49.56, 5.29};
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  return m;
}

// A sphere and a sheet, both with fibres, randomly perturbed by ~15 % of the edge length.
std::vector<geometry::TriMesh> test_meshes() {
  std::vector<geometry::TriMesh> meshes{icosphere(10, 2, 1.5, Tissue::kLvMyocardium, true),
                                        flat_sheet(7, 6, 2.0, 1.0, Tissue::kMitralLeaflet, {1, 1, 0})};
  return meshes;
}

std::vector<Vec3> perturbed(const std::vector<Vec3>& x, double amplitude, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  std::vector<Vec3> y = x;
  for (auto& p : y) p += Vec3(u(rng), u(rng), u(rng));
  return y;
}

using EnergyFn = std::function<double(const std::vector<Vec3>&)>;
using ForceFn = std::function<void(const std::vector<Vec3>&, std::vector<Vec3>&)>;

// Largest |F_k + dW/dx_k| over every coordinate, relative to the largest |F|.
double gradient_mismatch(const std::vector<Vec3>& x, const EnergyFn& energy, const ForceFn& force, double h) {
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  force(x, f);
  double fmax = 0, err = 0;
  for (const auto& v : f) fmax = std::max(fmax, v.cwiseAbs().maxCoeff());
  std::vector<Vec3> y = x;
  for (std::size_t i = 0; i < x.size(); ++i) {
    for (int d = 0; d < 3; ++d) {
      y[i][d] = x[i][d] + h;
      const double wp = energy(y);
      y[i][d] = x[i][d] - h;
      const double wm = energy(y);
      y[i][d] = x[i][d];
      err = std::max(err, std::abs(f[i][d] + (wp - wm) / (2 * h)));
    }
  }
  EXPECT_GT(fmax, 0);
  std::cout << "  relative mismatch |F + dW/dx| / max|F| = " << err / fmax << "\n";
  return err / fmax;
}

void expect_no_net_force_or_torque(const std::vector<Vec3>& x, const std::vector<Vec3>& f, const char* what) {
  Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
  double scale = 0, length = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    sum += f[i];
    torque += x[i].cross(f[i]);
    scale += f[i].norm();
    length = std::max(length, x[i].norm());
  }
  EXPECT_LT(sum.norm(), 1e-12 * scale) << what;
  EXPECT_LT(torque.norm(), 1e-12 * scale * length) << what;
}

TEST(StructureForces, SpringsAreMinusTheEnergyGradientForEveryLaw) {
  for (const auto& law : spring_laws()) {
    for (const auto& mesh : test_meshes()) {
      ShellOptions opt;
      opt.law = std::string(law.name);
      const ShellModel body(mesh, seed_materials(), opt);
      const auto x = perturbed(mesh.position_mm, 0.3, 7);
      const double mismatch = gradient_mismatch(
          x, [&](const auto& y) { return body.spring_energy(y); },
          [&](const auto& y, auto& f) { body.add_spring_forces(y, f); }, 1e-5);
      EXPECT_LT(mismatch, 1e-6) << law.name << " on " << mesh.name;
      std::vector<Vec3> f(x.size(), Vec3::Zero());
      body.add_spring_forces(x, f);
      expect_no_net_force_or_torque(x, f, "springs");
    }
  }
}

TEST(StructureForces, BendingIsMinusTheEnergyGradient) {
  for (const auto& mesh : test_meshes()) {
    const ShellModel body(mesh, seed_materials(), ShellOptions{});
    ASSERT_FALSE(body.hinges().empty());
    const auto x = perturbed(mesh.position_mm, 0.3, 11);
    const double mismatch = gradient_mismatch(
        x, [&](const auto& y) { return body.bending_energy(y); },
        [&](const auto& y, auto& f) { body.add_bending_forces(y, f); }, 1e-5);
    EXPECT_LT(mismatch, 1e-6) << mesh.name;
    std::vector<Vec3> f(x.size(), Vec3::Zero());
    body.add_bending_forces(x, f);
    expect_no_net_force_or_torque(x, f, "bending");
    // The stress-free mesh stores no bending energy and feels no bending force.
    EXPECT_NEAR(body.bending_energy(mesh.position_mm), 0, 1e-14);
  }
}

TEST(StructureForces, ActiveTensionIsMinusTheEnergyGradient) {
  for (const auto& mesh : test_meshes()) {
    ShellModel body(mesh, seed_materials(), ShellOptions{});
    std::vector<double> tension(mesh.node_count());
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(0, 50);
    for (auto& t : tension) t = u(rng);
    body.set_active_tension(tension);
    const auto x = perturbed(mesh.position_mm, 0.3, 5);
    const double mismatch = gradient_mismatch(
        x, [&](const auto& y) { return body.active_energy(y); },
        [&](const auto& y, auto& f) { body.add_active_forces(y, f); }, 1e-5);
    EXPECT_LT(mismatch, 1e-6) << mesh.name;
    std::vector<Vec3> f(x.size(), Vec3::Zero());
    body.add_active_forces(x, f);
    expect_no_net_force_or_torque(x, f, "active");
  }
}

// The area floor (ours): on meshes shrunk to 0.7 of their size and perturbed (area ratios about
// 0.2 to 0.8, J0 = 0.9: nearly every triangle inside the floor) its force is minus the gradient
// of its energy and carries no net force or torque; off (J0 = 0) it adds nothing.
TEST(StructureForces, AreaFloorIsMinusTheEnergyGradient) {
  for (const auto& mesh : test_meshes()) {
    ShellOptions opt;
    opt.area_floor = 0.9;
    const ShellModel body(mesh, seed_materials(), opt), off(mesh, seed_materials(), ShellOptions{});
    auto x = perturbed(mesh.position_mm, 0.3, 23);
    for (auto& p : x) p *= std::sqrt(0.5);
    const double mismatch = gradient_mismatch(
        x, [&](const auto& y) { return body.area_floor_energy(y); },
        [&](const auto& y, auto& f) { body.add_area_floor_forces(y, f); }, 1e-6);
    EXPECT_LT(mismatch, 1e-6) << mesh.name;
    std::vector<Vec3> f(x.size(), Vec3::Zero());
    body.add_area_floor_forces(x, f);
    expect_no_net_force_or_torque(x, f, "area floor");
    EXPECT_GT(body.area_floor_energy(x), 0);
    EXPECT_EQ(body.area_floor_energy(mesh.position_mm), 0);  // J = 1 > J0
    EXPECT_EQ(off.area_floor_energy(x), 0);
  }
}

TEST(StructureForces, TotalForceIsMinusTheTotalEnergyGradientWithPressure) {
  // A closed sphere: pressure work -p V is a potential too.
  const auto mesh = icosphere(10, 2, 1.5, Tissue::kLvMyocardium, true);
  ShellModel body(mesh, seed_materials(), ShellOptions{});
  body.set_cavity_pressure(1.3);
  std::vector<double> tension(mesh.node_count(), 20.0);
  body.set_active_tension(tension);
  const auto x = perturbed(mesh.position_mm, 0.3, 13);
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  const double mismatch = gradient_mismatch(
      x,
      [&](const auto& y) {
        return body.spring_energy(y) + body.bending_energy(y) + body.active_energy(y) -
               1.3 * cavity_volume_mm3(y, mesh.tri, 0.0);
      },
      [&](const auto&, auto& f) { f = body.forces_mn(); }, 1e-5);
  EXPECT_LT(mismatch, 1e-6);
  // Internal (springs + bending + active) forces: no net force or torque.
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  body.add_spring_forces(x, f);
  body.add_bending_forces(x, f);
  body.add_active_forces(x, f);
  expect_no_net_force_or_torque(x, f, "internal");
  // The pressure on a closed surface has no net force either.
  std::vector<Vec3> fp(x.size(), Vec3::Zero());
  body.add_pressure_forces(x, fp);
  Vec3 s = Vec3::Zero();
  for (const auto& v : fp) s += v;
  EXPECT_LT(s.norm(), 1e-12);
}

TEST(StructureForces, MassesSumToTheTissueMass) {
  const auto mesh = icosphere(10, 3, 2.0, Tissue::kLvMyocardium, false);
  const ShellModel body(mesh, seed_materials(), ShellOptions{});
  double m = 0, area = 0;
  for (double mi : body.masses_mg()) m += mi;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) area += mesh.area_mm2(t);
  EXPECT_NEAR(m, 1.05 * 2.0 * area, 1e-9 * m);  // eq 15
}

TEST(StructureForces, AlphaPhiAndLawsAgreeAtSmallStrain) {
  EXPECT_DOUBLE_EQ(alpha_phi(49.56, 5.29, 1.0), 49.56);
  EXPECT_DOUBLE_EQ(alpha_phi(49.56, 5.29, 0.0), 5.29);
  for (const auto& law : spring_laws()) {
    EXPECT_NEAR(law.tangent(0, 0.0133, 49.56, LawParams{}), 0.0133 * 49.56, 1e-12) << law.name;
    const double h = 1e-6;
    EXPECT_NEAR((law.stress(0.2 + h, 0.0133, 49.56, LawParams{}) - law.stress(0.2 - h, 0.0133, 49.56, LawParams{})) / (2 * h),
                law.tangent(0.2, 0.0133, 49.56, LawParams{}), 1e-6)
        << law.name;
  }
}

TEST(StructureInput, UnknownLawListsTheKnownOnes) {
  ShellOptions opt;
  opt.law = "hooke";
  try {
    ShellModel body(flat_sheet(3, 3, 1, 1, Tissue::kMitralLeaflet, {1, 0, 0}), seed_materials(), opt);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown spring law 'hooke'; known: fung, linear, neo_hookean, fung_tension"),
              std::string::npos)
        << e.what();
  }
}

TEST(StructureInput, NegativeThicknessStiffnessAndZeroAreaAreRejected) {
  auto expect_error = [](const geometry::TriMesh& mesh, const ShellMaterials& mat, const std::string& part) {
    try {
      ShellModel body(mesh, mat, ShellOptions{});
      ADD_FAILURE() << "no error for " << part;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
    }
  };
  auto sheet = flat_sheet(3, 3, 1, 1, Tissue::kMitralLeaflet, {1, 0, 0});
  auto thin = sheet;
  thin.thickness_mm[2] = -0.5;
  expect_error(thin, seed_materials(), "triangle 2 has thickness_mm = -0.5");
  auto soft = seed_materials();
  soft.tissue[static_cast<int>(Tissue::kMitralLeaflet)].c_kpa = -1;
  expect_error(sheet, soft, "tissue mitral_leaflet has c = -1 kPa");
  auto flat = sheet;
  flat.position_mm[flat.tri[0][2]] = 0.5 * (flat.position_mm[flat.tri[0][0]] + flat.position_mm[flat.tri[0][1]]);
  expect_error(flat, seed_materials(), "has zero area");
  auto light = seed_materials();
  light.density_mg_per_mm3 = 0;
  expect_error(sheet, light, "density = 0");
}

}  // namespace
}  // namespace systole::structure

namespace systole::structure {
namespace {

TEST(StructureConstraints, AnchorsStayAndMoveRigidlyWhenTold) {
  auto sheet = flat_sheet(6, 6, 1.0, 1.0, geometry::Tissue::kMitralLeaflet, {1, 0, 0});
  for (int i = 0; i < 6; ++i) sheet.region[i] |= geometry::kAnchor;  // the first row
  ShellOptions opt;
  opt.damping_per_ms = 0.5;
  ShellModel body(sheet, seed_materials(), opt);
  body.set_cavity_pressure(0.01);
  body.advance(20);
  for (int i = 0; i < 6; ++i) EXPECT_EQ(body.positions_mm()[i], sheet.position_mm[i]);  // fixed
  EXPECT_GT(body.positions_mm()[35].norm(), 0);
  EXPECT_NE(body.positions_mm()[35], sheet.position_mm[35]);  // free nodes moved
  // A rigid motion of the anchors is reached exactly at the end of the next advance.
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.1, Vec3::UnitZ()).toRotationMatrix();
  body.move_fixed_nodes(rot, Vec3(0.5, 0, 0));
  body.advance(5);
  for (int i = 0; i < 6; ++i)
    EXPECT_LT((body.positions_mm()[i] - (rot * sheet.position_mm[i] + Vec3(0.5, 0, 0))).norm(), 1e-12);
}

}  // namespace
}  // namespace systole::structure

namespace systole::structure {
namespace {

// A collapsing step's diagnosis names a triangle squeezed flat in its plane (ours): one node of
// a triangle moved to 5 % of the triangle's height from its opposite edge (in the triangle's
// plane, so the sphere does not fold) makes the hinges across that triangle's edges the stiffest
// rows; the undisturbed sphere has no such note.
TEST(StructureDiagnoses, TheStepLimiterNamesATriangleSqueezedFlat) {
  const auto mesh = icosphere(10, 2, 1.5, Tissue::kLvMyocardium, true);
  ShellModel body(mesh, seed_materials(), ShellOptions{});
  EXPECT_EQ(body.stable_step_limiter().find("squeezed flat"), std::string::npos) << body.stable_step_limiter();
  const double step_before = body.stable_step_ms();
  std::vector<Vec3> x = mesh.position_mm;
  const auto& t = mesh.tri[0];
  const Vec3 a = x[t[1]], b = x[t[2]];
  const Vec3 foot = a + (x[t[0]] - a).dot(b - a) / (b - a).squaredNorm() * (b - a);
  x[t[0]] = foot + 0.05 * (x[t[0]] - foot);
  body.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  const std::string what = body.stable_step_limiter();
  std::printf("  [measured] stable step %.3g -> %.3g ms: %s\n", step_before, body.stable_step_ms(), what.c_str());
  EXPECT_LT(body.stable_step_ms(), 0.5 * step_before);
  EXPECT_NE(what.find("squeezed flat to 0.05"), std::string::npos) << what;
}

// A flat, low isosceles triangle (base 2 mm, apex 0.3 mm above it, base nodes held) with its
// apex pushed towards the base by a constant in-plane load F (ours): the springs barely resist
// (the legs shorten by 4 % when it is flat), so without the area floor the apex passes through the
// base; with the floor it comes to rest where the floor's force balances F, J0^2/J^2 - 1 =
// F / (kappa s |bc| / 2) (the springs' share at that strain is < 1e-3 of F), and stays above it.
TEST(StructureAreaFloor, StopsATriangleFromBeingSqueezedFlat) {
  geometry::TriMesh mesh;
  mesh.name = "triangle";
  const double h = 0.3, s = 1.0;
  mesh.add_node({0, h, 0});
  mesh.add_node({-1, 0, 0}, geometry::kAnchor);
  mesh.add_node({1, 0, 0}, geometry::kAnchor);
  mesh.add_triangle(0, 1, 2, Tissue::kLvMyocardium, s, {1, 0, 0});
  const double load_mn = 20;
  auto run = [&](double floor) {
    ShellOptions opt;
    opt.area_floor = floor;
    opt.damping_per_ms = 20;
    ShellModel body(mesh, seed_materials(), opt);
    std::vector<Vec3> load(3, Vec3::Zero());
    load[0] = {0, -load_mn, 0};
    body.set_external_loads(load);
    double lowest = 1;
    for (int k = 0; k < 400; ++k) {
      body.advance(0.01);
      lowest = std::min(lowest, body.positions_mm()[0].y() / h);
      if (lowest < -0.5) break;  // passed through (further on, the legs would reach the strain limit)
    }
    return std::pair{lowest, body.positions_mm()[0].y() / h};
  };
  const auto [lowest_off, final_off] = run(0);
  EXPECT_LT(lowest_off, -0.5) << "without the floor the apex passes through the base";
  ShellOptions defaults;
  const double j0 = 0.5;
  const double j_eq = j0 / std::sqrt(1 + load_mn / (defaults.area_floor_modulus_kpa * s * 1.0));
  const auto [lowest_on, final_on] = run(j0);
  std::printf("  [measured] without the floor: lowest J %.3f, final %.3f; with J0 = %.1f: lowest %.4f, final %.4f "
              "(balance %.4f)\n", lowest_off, final_off, j0, lowest_on, final_on, j_eq);
  EXPECT_GT(lowest_on, 0.5 * j_eq);
  EXPECT_NEAR(final_on, j_eq, 0.01 * j_eq);
}

TEST(StructureThreads, TwoThreadsGiveTheSameForcesAndStableStep) {
  const auto mesh = icosphere(10, 3, 1.5, geometry::Tissue::kLvMyocardium, true);
  const auto x = perturbed(mesh.position_mm, 0.2, 17);
  ShellOptions one, two;
  two.threads = 2;
  ShellModel a(mesh, seed_materials(), one), b(mesh, seed_materials(), two);
  a.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  b.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
  double fmax = 0, diff = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    fmax = std::max(fmax, a.forces_mn()[i].norm());
    diff = std::max(diff, (a.forces_mn()[i] - b.forces_mn()[i]).norm());
  }
  EXPECT_LT(diff, 1e-12 * fmax);
  EXPECT_NEAR(a.stable_step_ms(), b.stable_step_ms(), 1e-12 * a.stable_step_ms());
  // 50 substeps from a smooth stretched state: the trajectories agree to round-off growth.
  std::vector<Vec3> y = perturbed(mesh.position_mm, 0.01, 19);
  for (auto& p : y) p *= 1.05;
  a.set_state(y, std::vector<Vec3>(y.size(), Vec3::Zero()));
  b.set_state(y, std::vector<Vec3>(y.size(), Vec3::Zero()));
  for (int k = 0; k < 50; ++k) {
    const double dt = a.stable_step_ms();
    a.substep(dt);
    b.substep(dt);
  }
  double dx = 0;
  for (std::size_t i = 0; i < y.size(); ++i) dx = std::max(dx, (a.positions_mm()[i] - b.positions_mm()[i]).norm());
  EXPECT_LT(dx, 1e-9);
}

}  // namespace
}  // namespace systole::structure

namespace systole::structure {
namespace {

// The mitral limiter: a clamped leaflet pushed towards -z by pressure stops at the limit and
// comes back when the load reverses; without the limiter it goes well beyond.
TEST(StructureConstraints, DisplacementLimiterHoldsTheLeaflet) {
  auto sheet = flat_sheet(11, 11, 1.0, 0.5, geometry::Tissue::kMitralLeaflet, {1, 0, 0});
  const double ymax = 10 * std::sqrt(3.0) / 2;
  for (std::size_t i = 0; i < sheet.node_count(); ++i) {
    const Vec3& p = sheet.position_mm[i];
    if (p.x() < 0.6 || p.x() > 9.4 || p.y() < 0.1 || p.y() > ymax - 0.1) sheet.region[i] |= geometry::kAnchor;
  }
  auto deepest = [&](const ShellModel& b) {
    double z = 0;
    for (const auto& p : b.positions_mm()) z = std::min(z, p.z());
    return z;
  };
  ShellOptions opt;
  opt.damping_per_ms = 0.3;
  ShellModel free_body(sheet, seed_materials(), opt), limited(sheet, seed_materials(), opt);
  limited.set_displacement_limit(-Vec3::UnitZ(), 0.5);
  for (ShellModel* b : {&free_body, &limited}) {
    b->set_cavity_pressure(0.02);  // normals +z: pushes towards -z
    b->advance(100);
  }
  EXPECT_LT(deepest(free_body), -1.0);
  EXPECT_GE(deepest(limited), -0.5 - 1e-12);
  EXPECT_LT(deepest(limited), -0.49);  // it does reach the limit
  std::cout << "  deepest node under load: limited " << deepest(limited) << " mm\n";
  limited.set_cavity_pressure(-0.02);
  limited.advance(100);
  EXPECT_GT(deepest(limited), -0.1);  // released: the leaflet moves back up
  std::cout << "  deepest node: free " << deepest(free_body) << " mm, limited (0.5 mm) then released "
            << deepest(limited) << " mm\n";
}

// The limiter measured from a given reference (a body built in another shape than its stress-free
// one, ours): the same sheet, built 0.3 mm below its stress-free plane and started there, may move
// 0.5 mm further down from the built shape (0.8 from the stress-free one) and no further; a wrong-
// sized reference is refused, and without one the limiter measures from the stress-free positions.
TEST(StructureConstraints, DisplacementLimiterMeasuresFromItsReference) {
  auto sheet = flat_sheet(11, 11, 1.0, 0.5, geometry::Tissue::kMitralLeaflet, {1, 0, 0});
  const double ymax = 10 * std::sqrt(3.0) / 2;
  std::vector<Vec3> built = sheet.position_mm;
  for (std::size_t i = 0; i < sheet.node_count(); ++i) {
    const Vec3& p = sheet.position_mm[i];
    if (p.x() < 0.6 || p.x() > 9.4 || p.y() < 0.1 || p.y() > ymax - 0.1) sheet.region[i] |= geometry::kAnchor;
    else built[i].z() -= 0.3;
  }
  ShellOptions opt;
  opt.damping_per_ms = 0.3;
  ShellModel body(sheet, seed_materials(), opt);
  EXPECT_EQ(body.displacement_limit_reference_mm().size(), 0u);
  body.set_displacement_limit(-Vec3::UnitZ(), 0.5);
  ASSERT_EQ(body.displacement_limit_reference_mm().size(), sheet.node_count());
  EXPECT_EQ(body.displacement_limit_reference_mm()[7], sheet.position_mm[7]);
  EXPECT_THROW(body.set_displacement_limit(-Vec3::UnitZ(), 0.5, std::vector<Vec3>(3, Vec3::Zero())), InputError);
  body.set_state(built, std::vector<Vec3>(sheet.node_count(), Vec3::Zero()));
  body.set_displacement_limit(-Vec3::UnitZ(), 0.5, built);
  body.set_cavity_pressure(0.02);  // normals +z: pushes towards -z
  body.advance(100);
  double deepest = 0, beyond_built = -1e300;
  for (std::size_t i = 0; i < sheet.node_count(); ++i) {
    deepest = std::min(deepest, body.positions_mm()[i].z());
    beyond_built = std::max(beyond_built, built[i].z() - body.positions_mm()[i].z());
  }
  EXPECT_LE(beyond_built, 0.5 + 1e-12);
  EXPECT_GE(deepest, -0.8 - 1e-12);
  EXPECT_LT(deepest, -0.79);  // it reaches the limit, 0.8 mm below the stress-free plane
  std::cout << "  deepest node under load, limit 0.5 mm from a shape built 0.3 mm down: " << deepest << " mm\n";
}

// The aortic cusps' radial limiter (ours): a pressurised sphere inflates beyond 1.05 of its
// radius from its z axis when free, and stays within that cylinder with the limiter; nodes that
// start outside the limit (none here) would keep their stress-free distance instead.
TEST(StructureConstraints, RadialLimiterHoldsTheNodesWithinTheCylinder) {
  const double r0 = 10, limit = 10.5;
  const auto mesh = icosphere(r0, 2, 1.5, geometry::Tissue::kAorticLeaflet, true);
  auto widest = [](const ShellModel& b) {
    double r = 0;
    for (const auto& p : b.positions_mm()) r = std::max(r, std::hypot(p.x(), p.y()));
    return r;
  };
  ShellOptions opt;
  opt.damping_per_ms = 0.3;
  ShellModel free_body(mesh, seed_materials(), opt), limited(mesh, seed_materials(), opt);
  limited.set_radial_limit(Vec3(0, 0, 3), Vec3(0, 0, -2), limit);  // any point on the axis, either sense
  for (ShellModel* b : {&free_body, &limited}) {
    b->set_cavity_pressure(0.05);
    b->advance(50);
  }
  std::cout << "  widest radius from the axis after 50 ms: free " << widest(free_body) << " mm, limited "
            << widest(limited) << " mm (limit " << limit << ")\n";
  EXPECT_GT(widest(free_body), limit + 0.5);  // the load does push beyond the limit
  EXPECT_LE(widest(limited), limit + 1e-9);
  EXPECT_GT(widest(limited), limit - 0.05);  // and the limited sphere reaches it
  EXPECT_THROW(limited.set_radial_limit(Vec3::Zero(), Vec3::UnitZ(), 0.0), InputError);
}

}  // namespace
}  // namespace systole::structure

namespace systole::structure {
namespace {
using geometry::Tissue;

// fung_tension (ours): eq 17 in tension below the exponent cap, its tangent continued linearly
// beyond (C1, bounded), and the small-strain modulus alone in compression.
TEST(StructureForces, FungTensionIsFungInTensionBoundedAndLinearInCompression) {
  const SpringLaw& law = find_spring_law("fung_tension");
  const SpringLaw& fung = find_spring_law("fung");
  const double c = 0.0133, a = 49.56, q_cap = 4;
  const LawParams lp{q_cap, 0};
  const double eps_cap = std::sqrt(q_cap / a);
  for (double e : {0.01, 0.1, 0.2, eps_cap})
    EXPECT_NEAR(law.stress(e, c, a, lp), fung.stress(e, c, a, lp), 1e-12 * fung.stress(e, c, a, lp)) << e;
  for (double e : {-0.05, -0.3, -0.6}) {
    EXPECT_DOUBLE_EQ(law.stress(e, c, a, lp), c * a * e);
    EXPECT_DOUBLE_EQ(law.tangent(e, c, a, lp), c * a);
  }
  const double k_max = c * a * std::exp(q_cap) * (1 + 2 * q_cap);
  const double h = 1e-7;
  EXPECT_NEAR(law.stress(eps_cap + h, c, a, lp) - law.stress(eps_cap - h, c, a, lp), 2 * h * k_max,
              1e-4 * 2 * h * k_max);  // C1 at the cap
  for (double e : {eps_cap + 0.01, 0.5, 0.9}) EXPECT_DOUBLE_EQ(law.tangent(e, c, a, lp), k_max) << e;
  EXPECT_LT(law.stress(0.5, c, a, lp), fung.stress(0.5, c, a, lp));
  // compression_fraction r: r = 1 is the capped Fung law in compression too; r = 0.5 halfway.
  const LawParams sym{q_cap, 1}, half{q_cap, 0.5};
  for (double e : {-0.05, -0.2}) {
    EXPECT_NEAR(law.stress(e, c, a, sym), fung.stress(e, c, a, lp), 1e-12 * std::abs(fung.stress(e, c, a, lp))) << e;
    EXPECT_NEAR(law.stress(e, c, a, half), 0.5 * (c * a * e + fung.stress(e, c, a, lp)), 1e-12) << e;
  }
  EXPECT_NEAR(law.stress(-0.5, c, a, sym), -law.stress(0.5, c, a, sym), 1e-12);  // odd when r = 1
}

// Length-tension (ours, ShellOptions::active_min_fibre_stretch = m): the active forces stay minus
// the gradient of W = tau s A g(lambda) across the branches lambda < m, [m, 1], > 1, and vanish
// on a sheet shortened along its fibres below m.
TEST(StructureForces, LengthTensionActiveForcesAreMinusTheEnergyGradientAndVanishBelowTheMinimum) {
  ShellOptions opt;
  opt.active_min_fibre_stretch = 0.8;
  for (const auto& mesh : test_meshes()) {
    ShellModel body(mesh, seed_materials(), opt);
    std::vector<double> tension(mesh.node_count());
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> u(0, 50);
    for (auto& t : tension) t = u(rng);
    body.set_active_tension(tension);
    std::vector<Vec3> x = mesh.position_mm;
    for (auto& p : x) p *= 0.88;  // fibre stretches spread over the three branches
    x = perturbed(x, 0.25, 9);
    const double mismatch = gradient_mismatch(
        x, [&](const auto& y) { return body.active_energy(y); },
        [&](const auto& y, auto& f) { body.add_active_forces(y, f); }, 1e-6);
    EXPECT_LT(mismatch, 1e-5) << mesh.name;
    std::vector<Vec3> f(x.size(), Vec3::Zero());
    body.add_active_forces(x, f);
    expect_no_net_force_or_torque(x, f, "active, length-tension");
  }
  // A sheet with fibres along x shortened uniformly to lambda = 0.75 < m along x: no active force.
  const auto sheet = flat_sheet(5, 5, 1.0, 1.0, Tissue::kLvMyocardium, {1, 0, 0});
  ShellModel body(sheet, seed_materials(), opt);
  body.set_active_tension(std::vector<double>(sheet.node_count(), 40.0));
  std::vector<Vec3> x = sheet.position_mm;
  for (auto& p : x) p.x() *= 0.75;
  std::vector<Vec3> f(x.size(), Vec3::Zero());
  body.add_active_forces(x, f);
  double fmax = 0;
  for (const auto& v : f) fmax = std::max(fmax, v.norm());
  EXPECT_EQ(fmax, 0.0);
  // and at lambda = 0.9 (f = 1 - (0.1 / 0.2)^2 = 0.75) the force is 0.75 of the seed's form
  ShellModel seed_form(sheet, seed_materials(), ShellOptions{});
  seed_form.set_active_tension(std::vector<double>(sheet.node_count(), 40.0));
  x = sheet.position_mm;
  for (auto& p : x) p.x() *= 0.9;
  std::vector<Vec3> f1(x.size(), Vec3::Zero()), f0(x.size(), Vec3::Zero());
  body.add_active_forces(x, f1);
  seed_form.add_active_forces(x, f0);
  for (std::size_t i = 0; i < x.size(); ++i) EXPECT_NEAR((f1[i] - 0.75 * f0[i]).norm(), 0, 1e-12 * (1 + f0[i].norm()));
}

}  // namespace
}  // namespace systole::structure
