// Loads (eq 11–14) and WSS (eq 27) on analytic fields: with u and p linear the MLS probe values
// and gradients are exact, so each marker's load must equal the closed form at its probe.
#include <gtest/gtest.h>

#include <cmath>

#include "solver/ibm/loads.h"
#include "solver/ibm/shapes.h"

namespace systole::ibm {
namespace {
using grid::Location;

const grid::Grid kGrid({16, 16, 16, 2.0, 2.0, 2.0});
const Eigen::Matrix3d kG = (Eigen::Matrix3d() << 0.2, 1.5, -0.3, 0.4, -0.5, 0.8, 0.0, 0.6, 0.3).finished();
const Vec3 kPressureGradient(0.7, -0.2, 1.1);
constexpr double kRe = 50;

struct LinearFlow {
  grid::XFaceField u;
  grid::YFaceField v;
  grid::ZFaceField w;
  grid::CellField p;
  explicit LinearFlow(const grid::Slabs& s) : u(s), v(s), w(s), p(s) {
    const Vec3 c(1, 1, 1);
    for (int k = -1; k <= u.k_count(); ++k)
      for (int j = -1; j <= kGrid.ny(); ++j)
        for (int i = -1; i <= kGrid.nx(); ++i) {
          const int kg = s.k_begin() + k;
          auto at = [&](Location L) -> Vec3 { return Vec3(kGrid.x(L, i), kGrid.y(L, j), kGrid.z(L, kg)) - c; };
          u(i, j, k) = kG.row(0).dot(at(Location::x_face));
          v(i, j, k) = kG.row(1).dot(at(Location::y_face));
          w(i, j, k) = kG.row(2).dot(at(Location::z_face));
          p(i, j, k) = 2.0 + kPressureGradient.dot(at(Location::cell));
        }
  }
};

double pressure_at(const Vec3& x) { return 2.0 + kPressureGradient.dot(x - Vec3(1, 1, 1)); }

TEST(Loads, OneSidedLoadsAndWssMatchTheClosedForm) {
  const grid::Slabs slabs(kGrid, MPI_COMM_WORLD);
  Markers markers(kGrid);
  BodyOptions o;
  o.mm_per_unit = 1.0;
  o.normals = ExpectedNormals::outward;
  markers.add_body(sphere_mesh(Vec3(1, 1, 1), 0.4, 2), "sphere", o);
  const Transfer t(slabs, markers);
  const LinearFlow f(slabs);
  std::vector<Vec3> accel(markers.size(), Vec3(0.3, 0.1, -0.4));
  const MarkerLoads L = compute_loads(t, {f.u, f.v, f.w}, f.p, kRe, accel);
  const Eigen::Matrix3d tau = (kG + kG.transpose()) / kRe;
  double worst_force = 0, worst_wss = 0, worst_p = 0;
  Vec3 nodal_total = Vec3::Zero();
  for (const auto& nodes : L.nodal_force)
    for (const Vec3& F : nodes) nodal_total += F;
  for (std::size_t b = 0; b < markers.size(); ++b) {
    const Vec3 &X = markers.markers().position[b], &n = markers.markers().normal[b];
    const double h = markers.h();
    const double pw = pressure_at(X + h * n) + h * accel[b].dot(n);  // eq 14
    const Vec3 tn = tau * n;
    const Vec3 F = (-pw * n + tn) * markers.markers().area[b];       // eq 11
    worst_p = std::max(worst_p, std::abs(L.wall_pressure[b] - pw));
    worst_force = std::max(worst_force, (L.force[b] - F).norm());
    worst_wss = std::max(worst_wss, std::abs(L.wss[b] - (tn - tn.dot(n) * n).norm()));
  }
  std::printf("  [measured] %zu markers: max |Δp| %.3g, max |ΔF| %.3g, max |ΔWSS| %.3g\n", markers.size(), worst_p,
              worst_force, worst_wss);
  EXPECT_LT(worst_p, 1e-12);
  EXPECT_LT(worst_force, 1e-14);
  EXPECT_LT(worst_wss, 1e-13);
  EXPECT_LT((nodal_total - L.total_force).norm(), 1e-13);
}

TEST(Loads, TwoSidedLoadsUseTheJumpAcrossTheSheet) {
  const grid::Slabs slabs(kGrid, MPI_COMM_WORLD);
  Markers markers(kGrid);
  BodyOptions o;
  o.mm_per_unit = 1.0;
  o.sides = Sides::two;
  markers.add_body(plate_with_hole_mesh(0.3, 0.3, 1.4, 1.0, 0.3, 3, 20), "leaflet-like plate", o);
  const Transfer t(slabs, markers);
  const LinearFlow f(slabs);
  const MarkerLoads L = compute_loads(t, {f.u, f.v, f.w}, f.p, kRe);
  double worst = 0;
  for (std::size_t b = 0; b < markers.size(); ++b) {
    const Vec3 &X = markers.markers().position[b], &n = markers.markers().normal[b];
    const double h = markers.h();
    // τ uniform: the viscous jump vanishes; p⁺ − p⁻ = 2h ∇p·n.
    const Vec3 F = -(pressure_at(X + h * n) - pressure_at(X - h * n)) * n * markers.markers().area[b];
    worst = std::max(worst, (L.force[b] - F).norm());
  }
  std::printf("  [measured] %zu markers: max |ΔF| (eq 12) %.3g\n", markers.size(), worst);
  EXPECT_LT(worst, 1e-14);
}

// A body filter loads only the bodies asked for: their loads equal the unfiltered call's bitwise
// (each marker's probes are its own), the others' are 0 and their nodes unloaded.
TEST(Loads, ABodyFilterLoadsOnlyThoseBodiesAndTheSameLoads) {
  const grid::Slabs slabs(kGrid, MPI_COMM_WORLD);
  Markers markers(kGrid);
  BodyOptions one;
  one.mm_per_unit = 1.0;
  one.normals = ExpectedNormals::outward;
  markers.add_body(sphere_mesh(Vec3(1, 1, 1), 0.4, 2), "sphere", one);
  BodyOptions two;
  two.mm_per_unit = 1.0;
  two.sides = Sides::two;
  markers.add_body(plate_with_hole_mesh(0.3, 0.3, 1.4, 1.0, 0.3, 3, 20), "plate", two);
  const Transfer t(slabs, markers);
  const LinearFlow f(slabs);
  const MarkerLoads all = compute_loads(t, {f.u, f.v, f.w}, f.p, kRe);
  const MarkerLoads plate = compute_loads(t, {f.u, f.v, f.w}, f.p, kRe, {}, {false, true});
  std::size_t on_plate = 0;
  for (std::size_t b = 0; b < markers.size(); ++b) {
    if (markers.markers().body[b] == 1) {
      ++on_plate;
      EXPECT_EQ(plate.force[b], all.force[b]) << b;
      EXPECT_EQ(plate.wall_pressure_minus[b], all.wall_pressure_minus[b]) << b;
    } else {
      EXPECT_EQ(plate.force[b], Vec3::Zero()) << b;
      EXPECT_NE(all.force[b], Vec3::Zero()) << b;
    }
  }
  EXPECT_GT(on_plate, 0u);
  for (const Vec3& F : plate.nodal_force[0]) EXPECT_EQ(F, Vec3::Zero());
  EXPECT_EQ(plate.nodal_force[1], all.nodal_force[1]);
  EXPECT_THROW(compute_loads(t, {f.u, f.v, f.w}, f.p, kRe, {}, {true}), std::invalid_argument);
}

// A body that moves within a cell of a z wall is a WallProximityError (naming the point), not an
// abort: the markers' rebuild checks every position alike on every rank, and the load probes
// (threaded above kThreadedMarkers points) rethrow after their OpenMP loop.
TEST(Loads, APointWithinACellOfTheWallIsAnErrorNotAnAbort) {
  const grid::Slabs slabs(kGrid, MPI_COMM_WORLD);
  Markers markers(kGrid);
  BodyOptions o;
  o.mm_per_unit = 1.0;
  o.normals = ExpectedNormals::outward;
  const int body = markers.add_body(sphere_mesh(Vec3(1, 1, 1), 0.4, 2), "sphere", o);
  Transfer t(slabs, markers);
  const LinearFlow f(slabs);
  // the sphere moved down until its lowest markers are half a cell from the wall z = 0
  markers.set_rigid_motion(body, Vec3(0, 0, -(0.6 - 0.5 * kGrid.dz())), Vec3(0, 0, 1), Vec3(1, 1, 1));
  markers.advance_rigid(1.0);
  try {
    t.rebuild();
    FAIL() << "no error";
  } catch (const WallProximityError& e) {
    EXPECT_LT(e.point().z(), kGrid.dz());
  }
  // many probe points, one of them a quarter cell from the wall z = 2
  std::vector<Vec3> points(static_cast<std::size_t>(kThreadedMarkers) + 10, Vec3(1, 1, 1));
  points[12345] = Vec3(1, 1, kGrid.lz() - 0.25 * kGrid.dz());
  try {
    (void)probe(Transfer(slabs, Markers(kGrid)), {f.u, f.v, f.w}, f.p, points);
    FAIL() << "no error";
  } catch (const WallProximityError& e) {
    EXPECT_EQ(e.point(), points[12345]);
  }
}

}  // namespace
}  // namespace systole::ibm
