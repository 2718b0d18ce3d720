// The rigid valvular plane by MLS direct forcing (MODEL.md §4; the seed uses eq 4, the
// first-external-node interpolation, for it): a full IB plate at z = 1 between the no-slip
// bottom wall z = 0 and the top wall z = 2, driven by a uniform body force G. The plate must act
// as a wall: the steady flow below it is plane Poiseuille u = G z (1 − z)/(2ν) (and the same
// above). Error relative to the exact peak G/(8ν); convergence under refinement.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "solver/fluid/fluid.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/plane_forcing.h"
#include "solver/ibm/shapes.h"

namespace systole::ibm {
namespace {

// switch_off_at > 0: the plate's markers are switched off at that time (the vein-ostia switch of
// MODEL.md §2) and the run continues to end_time; the reference is then the full channel.
// switch_off_at < 0: no body at all (the fluid alone over [0, 2]). profile (optional): u(z) out.
// first_node: the plate by the seed's eq 4 (PlaneForcing) instead of MLS markers.
double poiseuille_error(int cells_per_unit, double switch_off_at = 0, double end_time = 0.5,
                        std::vector<double>* profile = nullptr, bool first_node = false) {
  const int nz = 2 * cells_per_unit, nxy = 4;
  const double h = 1.0 / cells_per_unit;
  const grid::Grid g({nxy, nxy, nz, nxy * h, nxy * h, 2.0});
  const grid::Slabs slabs(g, MPI_COMM_WORLD);
  fluid::FluidParameters fp;
  fp.reynolds = 1;  // ν = 1
  fluid::FluidSolver fluid(slabs, fp);
  Markers markers(g);
  BodyOptions o;
  o.mm_per_unit = 1.0;
  const int plate = markers.add_body(plate_mesh(0, 0, g.lx(), g.ly(), 1.0, 2, 2), "valvular plane", o);
  DirectForcing forcing(slabs, markers, {});
  PlaneForcing eq4(slabs, RigidPlane{2, 1.0, [](double, double) { return true; }});
  if (first_node) {
    markers.set_active(plate, false);
    forcing.markers_moved();
  }
  const double G = 8.0;  // peak G/(8ν) = 1
  fluid.set_body_force([&](const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
    if (first_node) eq4.apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, Vec3(G, 0, 0));
    forcing.apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, Vec3(G, 0, 0));
    for (int k = 0; k < f.u.k_count(); ++k)
      for (int j = 0; j < nxy; ++j)
        for (int i = 0; i < nxy; ++i) f.u(i, j, k) += G;
  });
  auto exact = [&](double z) { const double s = z < 1 ? z : z - 1; return 0.5 * G * s * (1 - s); };
  fluid.set_velocity([&](double, double, double z) { return exact(z); }, [](double, double, double) { return 0.0; },
                     [](double, double, double) { return 0.0; });
  bool open = false;
  if (switch_off_at < 0) {
    markers.set_active(plate, false);
    forcing.markers_moved();
    eq4.set_active(false);
    open = true;
  }
  if (switch_off_at > 0) {
    fluid.advance_to(switch_off_at);
    markers.set_active(plate, false);
    forcing.markers_moved();  // the stencils of the active markers only
    eq4.set_active(false);
    open = true;
  }
  fluid.advance_to(end_time);  // 0.5: ≈ 5 decay times π²ν of the slowest transient
  // Open: Poiseuille over [0, 2], peak G/(2ν) = 4; the error is returned relative to it.
  auto reference = [&](double z) { return open ? 0.5 * G * z * (2 - z) : exact(z); };
  const double peak = open ? 0.5 * G : 1.0;
  double e = 0;
  for (int k = 0; k < fluid.velocity().u.k_count(); ++k) {
    const double z = g.z(grid::Location::x_face, slabs.k_begin() + k);
    e = std::max(e, std::abs(fluid.velocity().u(0, 0, k) - reference(z)));
    if (profile) profile->push_back(fluid.velocity().u(0, 0, k));
  }
  double out = 0;
  MPI_Allreduce(&e, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return out / peak;
}

// One MLS run and one eq 4 run per grid (h = 1/8, 1/16, 1/32) give four results:
// 1. The MLS plate acts as a wall: the error converges at first order (asserted ≥ 0.8 pairwise).
// 2. Where the diffuse MLS wall sits (the basis of the marker retraction, markers.h): below the
//    plate the steady flow is exactly u = G z (z_w − z)/(2ν) under the forcing zone; z_w from the
//    faces z < 1 − 2h (a one-parameter least-squares fit); (z_w − 1)/h is the fraction of a cell
//    by which the plate looks thicker (measured −0.454, −0.476, −0.483).
// 3. The seed's eq 4 (first node outside the body, linear interpolation to the wall; Fadlun et
//    al. 2000 J. Comput. Phys. 161:35): a sharp interface, second order (asserted ≥ 1.8).
// 4. Equivalence (issue 7: eq 4 "or MLS with a test showing equivalence"): the MLS profile
//    approaches eq 4's at first order; asserted on the least-squares slope over the three grids
//    (pairwise orders pre-asymptotic: measured 0.79 and 0.90).
TEST(IbmRigidPlane, MlsAndEq4PlatesPoiseuilleWallOffsetAndEquivalence) {
  double previous_mls = 0, previous_eq4 = 0, first_diff = 0, last_diff = 0;
  for (int n : {8, 16, 32}) {
    std::vector<double> mls, eq4;
    const double e = poiseuille_error(n, 0, 0.5, &mls, false);
    const double e4 = poiseuille_error(n, 0, 0.5, &eq4, true);
    const double h = 1.0 / n, G = 8.0;
    double num = 0, den = 0, diff = 0;
    for (std::size_t k = 0; k < mls.size(); ++k) {
      diff = std::max(diff, std::abs(mls[k] - eq4[k]));  // peak 1
      const double z = (static_cast<double>(k) + 0.5) * h;  // x-faces at cell-centre heights
      if (z > 1 - 2 * h) continue;
      const double a = 0.5 * G * z, r = mls[k] + 0.5 * G * z * z;  // u = a z_w − (G/2) z²
      num += a * r;
      den += a * a;
    }
    const double zw = num / den;
    std::printf("  [measured] h = 1/%d: MLS max |u − u_exact| / peak = %.4g, eq 4 = %.4g, |u_MLS − u_eq4| = %.4g,\n"
                "             MLS effective wall z_w = %.5f, offset (z_w - 1)/h = %.3f\n", n, e, e4, diff, zw, (zw - 1) / h);
    EXPECT_LT(zw, 1.0);  // the plate looks thicker on the fluid's side
    if (previous_mls > 0) {
      const double order = std::log2(previous_mls / e), order4 = std::log2(previous_eq4 / e4);
      std::printf("  [measured]   observed order MLS %.3f, eq 4 %.3f, difference %.3f\n", order, order4,
                  std::log2(last_diff / diff));
      EXPECT_GE(order, 0.8);
      EXPECT_GE(order4, 1.8);
    }
    if (first_diff == 0) first_diff = diff;
    last_diff = diff;
    previous_mls = e;
    previous_eq4 = e4;
  }
  const double order = std::log2(first_diff / last_diff) / 2;  // equally spaced log h: end-to-end slope
  std::printf("  [measured] MLS → eq 4, observed order (least squares, h = 1/8, 1/16, 1/32) %.3f\n", order);
  EXPECT_GE(order, 0.8);
}

// Switching the plate off (a marker set closing/opening an opening): the flow relaxes to plane
// Poiseuille over the whole channel [0, 2], G z(2 − z)/(2ν), peak 4: the same as a run of the
// fluid alone, up to the remaining transient.
TEST(IbmRigidPlane, SwitchingThePlateOffOpensTheChannel) {
  std::vector<double> switched, body_free;
  const double e = poiseuille_error(8, 0.5, 4.0, &switched);
  const double e_fluid = poiseuille_error(8, -1, 4.0, &body_free);
  double diff = 0;
  for (std::size_t k = 0; k < switched.size(); ++k) diff = std::max(diff, std::abs(switched[k] - body_free[k]));
  diff /= 4.0;  // the channel's peak
  std::printf("  [measured] plate switched off at t = 0.5, at t = 4: error vs the exact channel %.3g (the fluid\n"
              "             alone: %.3g, its O(h^2) wall error), difference to the body-free run %.3g\n", e, e_fluid, diff);
  // What is left is the transient of the slowest mode, 0.75 e^{−ν(π/2)²·3.5} ≈ 1.4e-4.
  EXPECT_LT(diff, 1e-3);
}

}  // namespace
}  // namespace systole::ibm
