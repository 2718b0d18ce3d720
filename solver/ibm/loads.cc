#include "solver/ibm/loads.h"

#include <mpi.h>

#include <array>
#include <stdexcept>
#include <string>

namespace systole::ibm {

using grid::Location;

ProbeValues probe(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                  const std::vector<Vec3>& points) {
  const grid::Grid& g = transfer.slabs().grid();
  const std::size_t n = points.size();
  // 10 values per point: p, then ∂u/∂x_j, ∂v/∂x_j, ∂w/∂x_j.
  std::vector<double> local(10 * n, 0.0), global(transfer.slabs().size() > 1 ? 10 * n : 0, 0.0);
  // Each point writes its own row: threads over points, no races.
  parallel_for_rethrow(static_cast<std::ptrdiff_t>(n), kThreadedMarkers, [&](std::ptrdiff_t qq) {
    const std::size_t q = static_cast<std::size_t>(qq);
    double* row = local.data() + 10 * q;
    // A point none of whose four supports is centred on this rank's planes is only checked
    // (every rank fails alike at a wall; its row stays 0 here): the full point with derivatives
    // is built by its owners only (ours, for cost; the rows are the same bitwise).
    if (!transfer.owns_plane(mls_k_centre_z_face(g, points[q])) && !transfer.owns_plane(mls_k_centre_cell(g, points[q]))) {
      mls_check_point(g, points[q]);
      return;
    }
    // The four locations share their 1-D weights; φ and ∂φ are contracted with the fields
    // row by row (mls.h, mls_point / mls_contract).
    const MlsPoint P = mls_point(g, points[q], true);
    if (transfer.owns_plane(mls_k_centre<Location::cell>(P)))
      row[0] = mls_contract<Location::cell, false>(p, P, nullptr);
    if (transfer.owns_plane(mls_k_centre<Location::x_face>(P)))
      (void)mls_contract<Location::x_face, true>(u.u, P, row + 1);
    if (transfer.owns_plane(mls_k_centre<Location::y_face>(P)))
      (void)mls_contract<Location::y_face, true>(u.v, P, row + 4);
    if (transfer.owns_plane(mls_k_centre<Location::z_face>(P)))
      (void)mls_contract<Location::z_face, true>(u.w, P, row + 7);
  });
  if (transfer.slabs().size() > 1)
    MPI_Allreduce(local.data(), global.data(), static_cast<int>(local.size()), MPI_DOUBLE, MPI_SUM,
                  transfer.slabs().comm());
  else
    global.swap(local);
  ProbeValues out;
  out.pressure.resize(n);
  out.velocity_gradient.resize(n);
  for (std::size_t q = 0; q < n; ++q) {
    const double* row = global.data() + 10 * q;
    out.pressure[q] = row[0];
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) out.velocity_gradient[q](i, j) = row[1 + 3 * i + j];
  }
  return out;
}

namespace {

// The probe points of the active markers: X_b + d h n for each d of `distances` (in cells),
// and X_b − d h n as well on two-sided bodies. plus[b] / minus[b]: the index of marker b's first
// point on each side (−1: none), its points for the following distances next to it.
struct ProbePoints {
  std::vector<Vec3> points;
  std::vector<std::ptrdiff_t> plus, minus;
};
// bodies: only the markers of these bodies (empty: every body's).
ProbePoints probe_points(const Markers& markers, const std::vector<double>& distances,
                         const std::vector<bool>& bodies = {}) {
  const MarkerArrays& m = markers.markers();
  const double h = markers.h();
  if (!bodies.empty() && bodies.size() != markers.bodies().size())
    throw std::invalid_argument("ibm loads: the body filter has " + std::to_string(bodies.size()) +
                                " entries for " + std::to_string(markers.bodies().size()) + " bodies");
  ProbePoints out;
  out.plus.assign(m.size(), -1);
  out.minus.assign(m.size(), -1);
  out.points.reserve(distances.size() * m.size());
  for (std::size_t b = 0; b < m.size(); ++b) {
    if (!markers.active(b) || (!bodies.empty() && !bodies[m.body[b]])) continue;
    out.plus[b] = static_cast<std::ptrdiff_t>(out.points.size());
    for (double d : distances) out.points.push_back(m.surface[b] + d * h * m.normal[b]);
    if (markers.bodies()[m.body[b]].options.sides == Sides::two) {
      out.minus[b] = static_cast<std::ptrdiff_t>(out.points.size());
      for (double d : distances) out.points.push_back(m.surface[b] - d * h * m.normal[b]);
    }
  }
  return out;
}

}  // namespace

MarkerLoads compute_loads(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                          double reynolds, const std::vector<Vec3>& acceleration, const std::vector<bool>& bodies) {
  const Markers& markers = transfer.markers();
  const MarkerArrays& m = markers.markers();
  const double h = markers.h();
  const std::size_t n = m.size();
  // Probes: "+" side for every active marker, "−" side for two-sided bodies.
  const ProbePoints pp = probe_points(markers, {1.0}, bodies);
  const std::vector<std::ptrdiff_t>& plus = pp.plus;
  const std::vector<std::ptrdiff_t>& minus = pp.minus;
  const ProbeValues pv = probe(transfer, u, p, pp.points);
  MarkerLoads L;
  L.force.assign(n, Vec3::Zero());
  L.wall_pressure.assign(n, 0.0);
  L.wall_pressure_minus.assign(n, 0.0);
  L.wss.assign(n, 0.0);
  L.wss_minus.assign(n, 0.0);
  L.nodal_force.resize(markers.bodies().size());
  for (std::size_t body = 0; body < markers.bodies().size(); ++body)
    L.nodal_force[body].assign(markers.bodies()[body].tiled.node_count(), Vec3::Zero());
  const double nu = 1.0 / reynolds;
  auto wss_of = [](const Vec3& t, const Vec3& nn) { return (t - t.dot(nn) * nn).norm(); };
  for (std::size_t b = 0; b < n; ++b) {
    if (plus[b] < 0) continue;
    const Vec3& nn = m.normal[b];
    const double an = acceleration.empty() ? 0.0 : acceleration[b].dot(nn);
    const Eigen::Matrix3d& Gp = pv.velocity_gradient[plus[b]];
    const Vec3 tp = nu * (Gp + Gp.transpose()) * nn;   // τ⁺·n      (eq 11, 27)
    const double pp = pv.pressure[plus[b]] + h * an;   // eq 14
    L.wall_pressure[b] = pp;
    L.wss[b] = wss_of(tp, nn);
    Vec3 F = (-pp * nn + tp) * m.area[b];               // eq 11
    if (minus[b] >= 0) {
      const Eigen::Matrix3d& Gm = pv.velocity_gradient[minus[b]];
      const Vec3 tm = nu * (Gm + Gm.transpose()) * nn;  // τ⁻·n⁺
      const double pm = pv.pressure[minus[b]] - h * an; // eq 14 on the − side
      L.wall_pressure_minus[b] = pm;
      L.wss_minus[b] = wss_of(tm, nn);
      F = (-(pp - pm) * nn + (tp - tm)) * m.area[b];    // eq 12
    }
    L.force[b] = F;
    L.total_force += F;
    for (int c = 0; c < 3; ++c) L.nodal_force[m.body[b]][m.node[b][c]] += F / 3.0;
  }
  return L;
}

WallShear wall_shear_stress(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                            double reynolds) {
  const Markers& markers = transfer.markers();
  const MarkerArrays& m = markers.markers();
  const std::size_t n = m.size();
  // Probe pairs (h, 2h) along +n for every active marker, along −n too for two-sided bodies.
  const ProbePoints pp = probe_points(markers, {1.0, 2.0});
  const std::vector<std::ptrdiff_t>& plus = pp.plus;
  const std::vector<std::ptrdiff_t>& minus = pp.minus;
  const ProbeValues pv = probe(transfer, u, p, pp.points);
  const double nu = 1.0 / reynolds;
  auto wss_at = [&](std::ptrdiff_t first, const Vec3& nn) {
    const Eigen::Matrix3d& G1 = pv.velocity_gradient[first];
    const Eigen::Matrix3d& G2 = pv.velocity_gradient[first + 1];
    const Vec3 t = nu * (2 * (G1 + G1.transpose()) - (G2 + G2.transpose())) * nn;  // 2 t(h) − t(2h)
    return (t - t.dot(nn) * nn).norm();
  };
  WallShear w;
  w.plus.assign(n, 0.0);
  w.minus.assign(n, 0.0);
  for (std::size_t b = 0; b < n; ++b) {
    if (plus[b] >= 0) w.plus[b] = wss_at(plus[b], m.normal[b]);
    if (minus[b] >= 0) w.minus[b] = wss_at(minus[b], m.normal[b]);
  }
  return w;
}

}  // namespace systole::ibm
