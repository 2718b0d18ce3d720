// Contact between different bodies (solver/structure/contact.h):
// - the closest point on a triangle against a dense brute-force search;
// - the penalty forces are minus the gradient of the penalty energy (also for nodes that have
//   crossed the other surface), sum to zero and carry no torque;
// - two clamped leaflet-like sheets pushed towards each other by a pressure do not cross, and
//   separate when the load reverses; with contact off the same sheets cross (the test can fail);
// - the candidate lists rebuilt per body (only the bodies that moved more than skin / 2) give
//   the contact forces of lists built afresh for every body;
// - the contact stiffness enters the reported stable step; bad options are rejected.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "solver/core/errors.h"
#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/topology.h"
#include "solver/structure/contact.h"
#include "solver/structure/shapes.h"

namespace systole::structure {
namespace {

using geometry::Tissue;

ShellMaterials seed_materials() {
  ShellMaterials m;
  for (auto& t : m.tissue) t = {13.3e-3, 49.56, 5.29};  // seed LV c (kPa), alpha_f, alpha_c
  m.density_mg_per_mm3 = 1.05;
  m.poisson_ratio = 0.5;
  return m;
}

// A flat sheet moved by `offset`, clamped on its boundary.
geometry::TriMesh clamped_sheet(int nx, int ny, double edge, double thickness, const Vec3& offset, const char* name) {
  auto mesh = flat_sheet(nx, ny, edge, thickness, Tissue::kMitralLeaflet, {1, 0, 0});
  for (auto& p : mesh.position_mm) p += offset;
  const geometry::EdgeTopology topo(mesh);
  for (const auto& loop : geometry::boundary_loops(mesh, topo))
    for (auto i : loop) mesh.region[i] |= geometry::kAnchor;
  mesh.name = name;
  return mesh;
}

TEST(StructureContact, ClosestPointOnTriangleMatchesABruteForceSearch) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2, 2);
  double worst = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 a(u(rng), u(rng), u(rng)), b(u(rng), u(rng), u(rng)), c(u(rng), u(rng), u(rng));
    const Vec3 x(u(rng), u(rng), u(rng));
    const TrianglePoint cp = closest_point_on_triangle(x, a, b, c);
    EXPECT_NEAR(cp.w[0] + cp.w[1] + cp.w[2], 1, 1e-12);
    for (double w : cp.w) EXPECT_GE(w, -1e-12);
    EXPECT_LT((cp.p - (cp.w[0] * a + cp.w[1] * b + cp.w[2] * c)).norm(), 1e-12);
    // Brute force: the best of a 400 x 400 barycentric grid can only be farther.
    double best = 1e300;
    const int m = 400;
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        const Vec3 q = a + (static_cast<double>(i) / m) * (b - a) + (static_cast<double>(j) / m) * (c - a);
        best = std::min(best, (x - q).norm());
      }
    const double d = (x - cp.p).norm();
    EXPECT_LE(d, best + 1e-12);
    worst = std::max(worst, best - d);
  }
  // The grid's spacing (<= 4 sqrt(3) * 2 / 400 mm) bounds how much farther the grid can be.
  EXPECT_LT(worst, 0.02);
  std::cout << "  largest (grid - exact) distance: " << worst << " mm\n";
}

// Penalty energy of the group as a function of all coordinates (sides as remembered).
struct GroupEnergy {
  BodyGroup& group;
  double operator()(std::size_t body, const std::vector<Vec3>& x) const {
    auto& b = group.body(body);
    b.set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
    group.refresh_contact();
    return group.contact_energy_uj();
  }
};

void check_gradient_momentum_torque(BodyGroup& group, const char* what) {
  group.refresh_contact();
  ASSERT_GT(group.contact_stats().active, 10) << what;
  std::vector<std::vector<Vec3>> x0, f0;
  for (std::size_t k = 0; k < group.body_count(); ++k) {
    x0.push_back(group.body(k).positions_mm());
    f0.push_back(group.contact_forces_mn(k));
  }
  // Momentum and torque of the contact forces.
  Vec3 sum = Vec3::Zero(), torque = Vec3::Zero();
  double scale = 0, fmax = 0;
  for (std::size_t k = 0; k < x0.size(); ++k)
    for (std::size_t i = 0; i < x0[k].size(); ++i) {
      sum += f0[k][i];
      torque += x0[k][i].cross(f0[k][i]);
      scale += f0[k][i].norm();
      fmax = std::max(fmax, f0[k][i].cwiseAbs().maxCoeff());
    }
  EXPECT_LT(sum.norm(), 1e-13 * scale) << what;
  EXPECT_LT(torque.norm(), 1e-13 * scale * 20) << what;
  std::cout << "  " << what << ": " << group.contact_stats().active << " active pairs, " << group.contact_stats().crossed
            << " crossed; |sum F| / sum|F| = " << sum.norm() / scale << ", |torque| / (sum|F| 20 mm) = "
            << torque.norm() / (scale * 20) << "\n";
  // F = -dW/dx by central differences on every coordinate of both bodies.
  GroupEnergy energy{group};
  const double h = 1e-6;
  double err = 0;
  for (std::size_t k = 0; k < x0.size(); ++k) {
    std::vector<Vec3> y = x0[k];
    for (std::size_t i = 0; i < y.size(); ++i)
      for (int d = 0; d < 3; ++d) {
        y[i][d] = x0[k][i][d] + h;
        const double wp = energy(k, y);
        y[i][d] = x0[k][i][d] - h;
        const double wm = energy(k, y);
        y[i][d] = x0[k][i][d];
        err = std::max(err, std::abs(f0[k][i][d] + (wp - wm) / (2 * h)));
      }
    energy(k, x0[k]);
  }
  std::cout << "  " << what << ": max |F + dW/dx| / max|F| = " << err / fmax << "\n";
  EXPECT_LT(err / fmax, 1e-6) << what;
}

TEST(StructureContact, PenaltyForcesAreMinusTheEnergyGradientWithoutNetForceOrTorque) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-0.05, 0.05);
  auto a = clamped_sheet(7, 7, 1.0, 0.5, Vec3::Zero(), "a");
  auto b = clamped_sheet(6, 7, 1.1, 0.5, Vec3(0.37, 0.21, 0.3), "b");
  for (auto* m : {&a, &b})
    for (auto& p : m->position_mm) p += Vec3(u(rng), u(rng), u(rng));
  // Stress-free meshes apart (no exclusions), then moved into contact 0.3 mm apart.
  auto a_far = a, b_far = b;
  for (auto& p : b_far.position_mm) p.z() += 5;
  BodyGroup group({ShellModel(a_far, seed_materials(), {}), ShellModel(b_far, seed_materials(), {})}, ContactOptions{});
  auto set = [&](std::size_t k, const std::vector<Vec3>& x) {
    group.body(k).set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
    group.refresh_contact();
  };
  // b approaches from above (its side is remembered from 1 mm away), then sits 0.3 mm above a.
  std::vector<Vec3> xb = b.position_mm;
  for (auto& p : xb) p.z() += 0.4;
  set(0, a.position_mm);
  set(1, xb);
  set(1, b.position_mm);
  check_gradient_momentum_torque(group, "0.3 mm apart");
  // b pushed 0.45 mm down: its nodes have crossed a (g < 0) and are pushed back up.
  xb = b.position_mm;
  for (auto& p : xb) p.z() -= 0.45;
  set(1, xb);
  EXPECT_GT(group.contact_stats().crossed, 5);
  double fz_b = 0;
  for (const auto& f : group.contact_forces_mn(1)) fz_b += f.z();
  EXPECT_GT(fz_b, 0);  // b is pushed back up, not through
  check_gradient_momentum_torque(group, "b pushed 0.15 mm through a");
}

// The viscous layer (ContactOptions::damping_ratio, ours): b sits 0.3 mm above a (inside the
// 0.5-mm layer). At rest the forces are the penalty's; b sliding along x drags a along and is
// held back by as much; b approaching is pushed harder; b leaving fast takes the push out but
// pulls no node of a whose closest point lies inside b's faces (away from the sheets' edges,
// where the closest point is on b's boundary and the relative velocity is partly tangential,
// so the drag acts along it). The forces on a and b sum to zero in every case.
TEST(StructureContact, TheViscousLayerDampsRelativeMotionWithoutPulling) {
  auto a = clamped_sheet(7, 7, 1.0, 0.5, Vec3::Zero(), "a");
  auto b = clamped_sheet(6, 7, 1.1, 0.5, Vec3(0.37, 0.21, 0.3), "b");
  auto b_far = b;
  for (auto& p : b_far.position_mm) p.z() += 5;
  ContactOptions o;
  o.damping_ratio = 1;
  BodyGroup group({ShellModel(a, seed_materials(), {}), ShellModel(b_far, seed_materials(), {})}, o);
  auto with_b_velocity = [&](const Vec3& v_mm_per_ms) {
    std::vector<Vec3> xb = b.position_mm;
    for (auto& p : xb) p.z() += 0.4;  // from 0.7 mm away: b's side is remembered
    group.body(1).set_state(xb, std::vector<Vec3>(xb.size(), Vec3::Zero()));
    group.refresh_contact();
    group.body(1).set_state(b.position_mm, std::vector<Vec3>(b.position_mm.size(), v_mm_per_ms));
    group.refresh_contact();
    Vec3 on_a = Vec3::Zero(), on_b = Vec3::Zero();
    for (const auto& f : group.contact_forces_mn(0)) on_a += f;
    for (const auto& f : group.contact_forces_mn(1)) on_b += f;
    EXPECT_LT((on_a + on_b).norm(), 1e-12 * (on_a.norm() + 1e-300));
    return on_a;
  };
  const Vec3 rest = with_b_velocity(Vec3::Zero());
  ASSERT_GT(group.contact_stats().active, 10);
  EXPECT_LT(rest.z(), 0);  // a pushed down, away from b
  EXPECT_LT(std::abs(rest.x()), 0.02 * std::abs(rest.z()));  // the edges' lateral pushes
  const Vec3 sliding = with_b_velocity(Vec3(1, 0, 0));  // 1 m/s along x
  EXPECT_GT(sliding.x() - rest.x(), 0.05 * std::abs(rest.z()));  // dragged along
  EXPECT_NEAR(sliding.z(), rest.z(), 0.02 * std::abs(rest.z()));
  const Vec3 approaching = with_b_velocity(Vec3(0, 0, -1));
  EXPECT_LT(approaching.z(), 1.5 * rest.z());  // pushed harder
  const Vec3 leaving = with_b_velocity(Vec3(0, 0, 50));
  int inner = 0;
  for (std::size_t i = 0; i < group.body(0).node_count(); ++i) {
    const Vec3& x = group.body(0).positions_mm()[i];
    if (x.x() < 1.5 || x.x() > 5 || x.y() < 1.5 || x.y() > 4.5) continue;
    ++inner;
    EXPECT_LE(group.contact_forces_mn(0)[i].z(), 0) << "node " << i << " of a pulled towards b";
  }
  EXPECT_GT(inner, 6);
  std::cout << "  viscous layer, sum of the forces on a (mN): at rest " << rest.transpose() << "; b sliding at 1 m/s "
            << sliding.transpose() << "; approaching " << approaching.transpose() << "; leaving at 50 m/s "
            << leaving.transpose() << "\n";
}

struct SheetRun {
  double min_gap_loaded_mm = 1e300;  // smallest vertical distance between the surfaces while loaded
  double centre_gap_loaded_mm = 0;   // at the end of the loading phase
  double centre_gap_released_mm = 0; // at the end of the reversed load
  double min_gap_released_mm = 1e300;
  double stable_step_free_ms = 0, stable_step_contact_ms = 0;
  int crossed_max = 0;
};

// Vertical distance z_b(x, y) - z_a over the free nodes of a, with z_b interpolated on b's
// deformed triangle that contains (x, y) in projection (both sheets stay graphs over the
// plane), and the same for the nodes of b against a's surface. Independent of the contact code.
double min_vertical_gap(const ShellModel& a, const ShellModel& b) {
  double gap = 1e300;
  auto one_way = [&gap](const ShellModel& lower, const ShellModel& upper, double sign) {
    const auto& xl = lower.positions_mm();
    const auto& xu = upper.positions_mm();
    for (std::size_t i = 0; i < xl.size(); ++i) {
      if (lower.fixed()[i]) continue;
      for (const auto& t : upper.stress_free_mesh().tri) {
        const Vec3 &p0 = xu[t[0]], &p1 = xu[t[1]], &p2 = xu[t[2]];
        const double det = (p1.x() - p0.x()) * (p2.y() - p0.y()) - (p2.x() - p0.x()) * (p1.y() - p0.y());
        const double l1 = ((xl[i].x() - p0.x()) * (p2.y() - p0.y()) - (p2.x() - p0.x()) * (xl[i].y() - p0.y())) / det;
        const double l2 = ((p1.x() - p0.x()) * (xl[i].y() - p0.y()) - (xl[i].x() - p0.x()) * (p1.y() - p0.y())) / det;
        if (l1 < -1e-12 || l2 < -1e-12 || l1 + l2 > 1 + 1e-12) continue;
        const double z = p0.z() + l1 * (p1.z() - p0.z()) + l2 * (p2.z() - p0.z());
        gap = std::min(gap, sign * (z - xl[i].z()));
        break;
      }
    }
  };
  one_way(a, b, 1);   // b above a's nodes
  one_way(b, a, -1);  // a below b's nodes
  return gap;
}

double centre_gap(const ShellModel& a, const ShellModel& b, const Vec3& centre) {
  auto nearest_z = [&](const ShellModel& m) {
    std::size_t best = 0;
    const auto& X = m.stress_free_mesh().position_mm;
    for (std::size_t i = 1; i < X.size(); ++i)
      if ((X[i] - centre).head<2>().norm() < (X[best] - centre).head<2>().norm()) best = i;
    return m.positions_mm()[best].z();
  };
  return nearest_z(b) - nearest_z(a);
}

// Two clamped leaflet-like sheets (mitral tissue, 0.5 mm thick), 1 mm apart, of different
// resolutions (1.0 and 0.9 mm edges) and offset in the plane so that no node faces a node;
// a pressure of 0.05 kPa bulges each towards the other for 100 ms, then reverses for 100 ms.
SheetRun run_two_sheets(bool contact_on, ContactRule rule = ContactRule::kPenalty, double cell_mm = 0.5) {
  const Vec3 centre(6.0, 5.2, 0);
  auto a = clamped_sheet(13, 13, 1.0, 0.5, Vec3::Zero(), "lower");
  auto b = clamped_sheet(14, 15, 0.9, 0.5, Vec3(0.3, 0.2, 1.0), "upper");
  ShellOptions opt;
  opt.damping_per_ms = 0.3;
  ContactOptions copt;
  copt.enabled = contact_on;
  copt.rule = rule;
  copt.distance_mm = cell_mm;
  BodyGroup group({ShellModel(a, seed_materials(), opt), ShellModel(b, seed_materials(), opt)}, copt);
  SheetRun r;
  r.stable_step_free_ms = group.stable_step_ms();
  // Normals +z: a positive pressure pushes towards -z.
  const double p = 0.05;
  group.body(0).set_cavity_pressure(-p);  // lower sheet up
  group.body(1).set_cavity_pressure(p);   // upper sheet down
  for (int k = 0; k < 200; ++k) {  // sampled every 0.5 ms
    group.advance(0.5);
    r.min_gap_loaded_mm = std::min(r.min_gap_loaded_mm, min_vertical_gap(group.body(0), group.body(1)));
    r.crossed_max = std::max(r.crossed_max, group.contact_stats().crossed);
  }
  r.stable_step_contact_ms = group.stable_step_ms();
  r.centre_gap_loaded_mm = centre_gap(group.body(0), group.body(1), centre);
  group.body(0).set_cavity_pressure(p);
  group.body(1).set_cavity_pressure(-p);
  for (int k = 0; k < 200; ++k) {
    group.advance(0.5);
    r.min_gap_released_mm = std::min(r.min_gap_released_mm, min_vertical_gap(group.body(0), group.body(1)));
  }
  r.centre_gap_released_mm = centre_gap(group.body(0), group.body(1), centre);
  return r;
}

TEST(StructureContact, TwoSheetsPushedTogetherDoNotCrossAndSeparateWhenTheLoadReverses) {
  const SheetRun on = run_two_sheets(true);
  const SheetRun off = run_two_sheets(false);
  std::cout << "  contact on : min vertical gap while loaded " << on.min_gap_loaded_mm << " mm, centre gap "
            << on.centre_gap_loaded_mm << " mm loaded -> " << on.centre_gap_released_mm << " mm released (min "
            << on.min_gap_released_mm << " mm); crossed pairs (max) " << on.crossed_max << "; stable step "
            << on.stable_step_free_ms << " ms apart, " << on.stable_step_contact_ms << " ms in contact\n"
            << "  contact off: min vertical gap while loaded " << off.min_gap_loaded_mm << " mm, centre gap "
            << off.centre_gap_loaded_mm << " mm loaded -> " << off.centre_gap_released_mm << " mm released\n";
  // With contact: the surfaces never cross; they stay at least half the contact distance apart.
  EXPECT_GT(on.min_gap_loaded_mm, 0.25);
  EXPECT_EQ(on.crossed_max, 0);
  // They did touch: the centre gap closed from 1 mm to about the contact distance.
  EXPECT_LT(on.centre_gap_loaded_mm, 0.6);
  // Released: they separate beyond their initial 1 mm distance.
  EXPECT_GT(on.centre_gap_released_mm, 1.5);
  EXPECT_GT(on.min_gap_released_mm, 0.25);
  // The contact stiffness entered the reported stable step.
  EXPECT_LT(on.stable_step_contact_ms, 0.9 * on.stable_step_free_ms);
  // Without contact the same sheets pass through each other.
  EXPECT_LT(off.min_gap_loaded_mm, -1.0);
  EXPECT_LT(off.centre_gap_loaded_mm, -1.0);
  // The seed's cell-averaging rule on the same case (cells of d_c = 0.5 mm), for comparison.
  // Cells of d_c = 0.5 mm and of 1.4 mm (the seed's ratio: marker spacing = 0.7 cell).
  for (double cell_mm : {0.5, 1.4}) {
    const SheetRun cell = run_two_sheets(true, ContactRule::kCellAverage, cell_mm);
    std::cout << "  cell rule (" << cell_mm << " mm cells): min vertical gap while loaded " << cell.min_gap_loaded_mm
              << " mm, centre gap " << cell.centre_gap_loaded_mm << " mm loaded -> " << cell.centre_gap_released_mm
              << " mm released (min " << cell.min_gap_released_mm << " mm)\n";
  }
}

// The procedural heart's two mitral leaflets (default geometry, seed tissue), anchored at the
// annulus, closed by a small LV-over-LA pressure with the seed's limiter on (1 mm towards the
// LA). Independent measure of crossing: for every free-edge node of the anterior leaflet, its
// x minus the x of the posterior free-edge node nearest in y (the free edges start 2 mm apart
// along x; negative = crossed).
struct MitralRun {
  double dx_initial = 0, dx_min_loaded = 1e300, dx_loaded = 0;
  double towards_la_max = 0;  // largest displacement of a leaflet node towards the LA (-z)
  int crossed_max = 0;
};

MitralRun run_mitral(bool contact_on, double load_ms, bool limiter_on = true) {
  config::Scenario s = config::default_scenario();
  // The seed's leaflet c in pascals (soft leaflets that a 0.3 mmHg load brings together; the
  // default reads it in units of rho U^2, docs/fsei.md): this test is about the contact.
  s.tissue.mitral_leaflets.fung_c_pa = 9.7;
  const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
  const auto& A = heart.body(geometry::kMitralAnteriorBody);
  const auto& P = heart.body(geometry::kMitralPosteriorBody);
  ShellOptions opt;
  opt.damping_per_ms = 0.3;
  ContactOptions copt;
  copt.enabled = contact_on;
  BodyGroup group({ShellModel(A, materials_from_config(s.tissue), opt), ShellModel(P, materials_from_config(s.tissue), opt)},
                  copt);
  if (limiter_on)
    for (std::size_t k = 0; k < 2; ++k) group.body(k).set_displacement_limit(-Vec3::UnitZ(), 1.0);
  auto free_edge_dx = [&] {
    const auto& xa = group.body(0).positions_mm();
    const auto& xp = group.body(1).positions_mm();
    double dx = 1e300;
    for (std::size_t i = 0; i < xa.size(); ++i) {
      if (!(A.region[i] & geometry::kFreeEdge)) continue;
      std::size_t best = 0;
      double by = 1e300;
      for (std::size_t j = 0; j < xp.size(); ++j)
        if ((P.region[j] & geometry::kFreeEdge) && std::abs(xp[j].y() - xa[i].y()) < by) {
          by = std::abs(xp[j].y() - xa[i].y());
          best = j;
        }
      dx = std::min(dx, xa[i].x() - xp[best].x());
    }
    return dx;
  };
  auto towards_la = [&] {
    double d = 0;
    for (std::size_t k = 0; k < 2; ++k)
      for (std::size_t i = 0; i < group.body(k).node_count(); ++i)
        d = std::max(d, group.body(k).stress_free_mesh().position_mm[i].z() - group.body(k).positions_mm()[i].z());
    return d;
  };
  MitralRun r;
  r.dx_initial = free_edge_dx();
  // Leaflet normals point towards the LA (-z), so the LV-over-LA pressure enters with a minus.
  const double p_kpa = 0.04;  // 0.3 mmHg: the seed-c leaflets alone (no fluid, no chordae)
                              // collapse within ~45 ms under it (docs/structure.md)
  for (std::size_t k = 0; k < 2; ++k) group.body(k).set_cavity_pressure(-p_kpa);
  for (double t = 0; t < load_ms; t += 1) {
    group.advance(1);
    r.dx_min_loaded = std::min(r.dx_min_loaded, free_edge_dx());
    r.towards_la_max = std::max(r.towards_la_max, towards_la());
    r.crossed_max = std::max(r.crossed_max, group.contact_stats().crossed);
  }
  r.dx_loaded = free_edge_dx();
  return r;
}

TEST(StructureContact, MitralLeafletsCoaptWithoutCrossingUnderTheLimiter) {
  const MitralRun on = run_mitral(true, 35), off = run_mitral(false, 35), free = run_mitral(true, 35, false);
  std::cout << "  contact on : free-edge dx " << on.dx_initial << " mm at rest, min " << on.dx_min_loaded
            << " mm while loaded, " << on.dx_loaded << " mm at 35 ms; largest displacement towards the LA " << on.towards_la_max
            << " mm (limit 1); crossed pairs (max) " << on.crossed_max << "\n"
            << "  contact off: free-edge dx min " << off.dx_min_loaded << " mm, " << off.dx_loaded << " mm at 35 ms\n"
            << "  limiter off: largest displacement towards the LA " << free.towards_la_max << " mm, free-edge dx min "
            << free.dx_min_loaded << " mm\n";
  EXPECT_GT(on.dx_initial, 1.5);
  EXPECT_GT(on.dx_min_loaded, 0.25);   // never crossed (the layer holds them d_c = 0.5 mm apart)
  EXPECT_LT(on.dx_loaded, 0.75);       // coapted
  EXPECT_EQ(on.crossed_max, 0);
  EXPECT_LE(on.towards_la_max, 1.0 + 1e-9);
  EXPECT_GT(free.towards_la_max, 1.2);   // without it they go past the 1 mm limit
  EXPECT_GT(free.dx_min_loaded, 0.25);   // contact holds without the limiter too
  EXPECT_LT(off.dx_loaded, -1.0);      // without contact the free edges pass each other
}

// Bodies over two OpenMP threads: every body's arithmetic is the same as on one thread, so the
// trajectories (with contact) agree exactly.
TEST(StructureContact, BodiesOverTwoThreadsGiveTheSameTrajectories) {
  // Few substeps: an OpenMP barrier on a loaded 2-core machine can cost tens of ms.
  auto a = clamped_sheet(9, 9, 1.0, 0.5, Vec3::Zero(), "lower");
  auto b = clamped_sheet(10, 10, 0.9, 0.5, Vec3(0.3, 0.2, 5.0), "upper");
  std::vector<Vec3> xb = b.position_mm;
  for (auto& p : xb) p.z() = 0.45;  // inside the contact layer of a
  std::vector<std::vector<Vec3>> end;
  for (int threads : {1, 2}) {
    BodyGroup group({ShellModel(a, seed_materials(), {}), ShellModel(b, seed_materials(), {})}, ContactOptions{}, threads);
    group.body(1).set_state(xb, std::vector<Vec3>(xb.size(), Vec3::Zero()));
    group.refresh_contact();
    group.body(0).set_cavity_pressure(-0.05);
    group.body(1).set_cavity_pressure(0.05);
    const double dt = group.stable_step_ms();
    for (int k = 0; k < 10; ++k) group.substep(dt);
    EXPECT_GT(group.contact_stats().active, 10);
    end.push_back(group.body(0).positions_mm());
    end.push_back(group.body(1).positions_mm());
  }
  double diff = 0;
  for (int k = 0; k < 2; ++k)
    for (std::size_t i = 0; i < end[k].size(); ++i) diff = std::max(diff, (end[k][i] - end[k + 2][i]).norm());
  EXPECT_EQ(diff, 0.0);
}

TEST(StructureContact, ListsRebuiltOnlyForTheBodiesThatMovedGiveTheForcesOfAFreshBuild) {
  // Three sheets stacked 0.3 mm apart (inside each other's layer, d_c = 0.5 mm), uncrossed, so
  // the remembered sides do not matter; their stress-free meshes far apart (no exclusions).
  std::vector<geometry::TriMesh> far;
  for (int k = 0; k < 3; ++k)
    far.push_back(clamped_sheet(7, 7, 1.0, 0.5, Vec3(0.1 * k, 0.07 * k, 10.0 * k), ("sheet " + std::to_string(k)).c_str()));
  auto stacked = [&](int k, double dz, double dx) {
    std::vector<Vec3> x = far[static_cast<std::size_t>(k)].position_mm;
    for (auto& p : x) p += Vec3(dx, 0, 0.3 * k + dz - 10.0 * k);
    return x;
  };
  std::vector<ShellModel> bodies;
  for (const auto& m : far) bodies.emplace_back(m, seed_materials(), ShellOptions{});
  BodyGroup group(bodies, ContactOptions{});  // skin 0.25 mm: a body re-hashed beyond 0.125 mm
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> small(-0.02, 0.02);
  // Each step moves sheet 2 sideways by 1.5 mm (a re-hash) and sheets 0 and 1 by less than the
  // skin's half in total (no re-hash), so most rebuilds re-hash one body of three.
  std::vector<double> dz(3, 0.0);
  long builds_at_1 = 0, bodies_at_1 = 0;
  for (int step = 0; step < 8; ++step) {
    if (step == 1) builds_at_1 = group.contact_stats().candidate_builds, bodies_at_1 = group.contact_stats().body_rebuilds;
    for (int k = 0; k < 2; ++k) dz[static_cast<std::size_t>(k)] = small(rng);
    for (int k = 0; k < 3; ++k) {
      const auto x = stacked(k, dz[static_cast<std::size_t>(k)], k == 2 ? 1.5 * (step % 2) : 0.0);
      group.body(static_cast<std::size_t>(k)).set_state(x, std::vector<Vec3>(x.size(), Vec3::Zero()));
    }
    group.refresh_contact();
    BodyGroup fresh(bodies, ContactOptions{});
    for (std::size_t k = 0; k < 3; ++k) fresh.body(k).set_state(group.body(k).positions_mm(), group.body(k).velocities_mm_per_ms());
    fresh.refresh_contact();
    ASSERT_GT(group.contact_stats().active, 20) << "step " << step;
    EXPECT_EQ(group.contact_stats().active, fresh.contact_stats().active) << "step " << step;
    EXPECT_EQ(group.contact_stats().crossed, 0);
    for (std::size_t k = 0; k < 3; ++k)
      for (std::size_t i = 0; i < group.body(k).node_count(); ++i)
        EXPECT_NEAR((group.contact_forces_mn(k)[i] - fresh.contact_forces_mn(k)[i]).norm(), 0.0, 1e-12)
            << "step " << step << ", sheet " << k << ", node " << i;
  }
  // From the stacked start on, one build per step, each re-hashing sheet 2 alone (the others
  // stayed within 0.04 mm of their positions at step 0).
  EXPECT_EQ(group.contact_stats().candidate_builds - builds_at_1, 7);
  EXPECT_EQ(group.contact_stats().body_rebuilds - bodies_at_1, 7);
}

TEST(StructureContact, BadOptionsAreRejected) {
  auto a = clamped_sheet(4, 4, 1.0, 0.5, Vec3::Zero(), "a");
  auto make = [&](double d, double k, double skin, double zeta = 0) {
    ContactOptions o;
    o.distance_mm = d;
    o.stiffness_kpa_per_mm = k;
    o.skin_mm = skin;
    o.damping_ratio = zeta;
    return BodyGroup({ShellModel(a, seed_materials(), {})}, o);
  };
  EXPECT_THROW(make(0.5, 40, 0.25, -0.1), InputError);
  EXPECT_THROW(make(0.5, 40, 0.25, 2.5), InputError);
  try {
    make(0.5, 40, 0.25, 3);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("damping_ratio = 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make(0, 40, 0.25), InputError);
  EXPECT_THROW(make(0.5, -1, 0.25), InputError);
  EXPECT_THROW(make(0.5, 40, 0), InputError);
  try {
    make(-0.5, 40, 0.25);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("distance_mm = -0.5"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace systole::structure

namespace systole::structure {
namespace {

// A diagnosis of a collapsing step names what sets it (ours): the body with the smallest
// stable step and its stiffest node. Here the smaller, stiffer sphere (its Gershgorin row per
// mass is 4x the larger one's: the same mesh at half the size).
TEST(BodyGroup, TheStableStepsLimiterIsTheStiffestBodysNode) {
  auto small = icosphere(5, 2, 1.0, geometry::Tissue::kLvMyocardium, false);
  small.name = "small";
  auto large = icosphere(10, 2, 1.0, geometry::Tissue::kLvMyocardium, false);
  large.name = "large";
  for (auto& p : large.position_mm) p.x() += 40;  // far apart: no contact pair acts
  BodyGroup group({ShellModel(large, seed_materials(), {}), ShellModel(small, seed_materials(), {})}, ContactOptions{});
  const std::string what = group.stable_step_limiter();
  EXPECT_NE(what.find("body 'small' node "), std::string::npos) << what;
  EXPECT_NE(what.find("row/mass"), std::string::npos) << what;
  EXPECT_EQ(group.stable_step_ms(), group.body(1).stable_step_ms());
}

}  // namespace
}  // namespace systole::structure
