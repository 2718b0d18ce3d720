#include "solver/ibm/plane_forcing.h"

#include <mpi.h>

#include <cmath>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::ibm {

using grid::Location;

namespace {
// The forced nodes of one component: flat indices of x₁ and x₂ in the field's storage and the
// interpolation factor d₁/(d₁ + Δ) (0 for a node on the plane).
struct Node {
  std::ptrdiff_t first, second;
  double factor;
};

template <grid::Location L>
std::vector<Node> forced_nodes_of(const grid::Slabs& slabs, const RigidPlane& plane, const grid::Field<L>& f) {
  const grid::Grid& g = slabs.grid();
  const double spacing[3] = {g.dx(), g.dy(), g.dz()};
  const double offset[3] = {L == Location::x_face ? 0.0 : 0.5, L == Location::y_face ? 0.0 : 0.5,
                            L == Location::z_face ? 0.0 : 0.5};
  const int a = plane.axis;
  const int first_in_plane = a == 0 ? 1 : 0, second_in_plane = a == 2 ? 1 : 2;  // increasing order
  const double D = spacing[a];
  std::vector<Node> out;
  const int kb = slabs.k_begin();
  for (int k = 0; k < f.k_count(); ++k) {
    if (L == Location::z_face && kb + k == 0) continue;  // the bottom wall face (w = 0 there)
    for (int j = 0; j < f.ny(); ++j)
      for (int i = 0; i < f.nx(); ++i) {
        const int idx[3] = {i, j, kb + k};
        double x[3];
        for (int d = 0; d < 3; ++d) x[d] = (idx[d] + offset[d]) * spacing[d];
        const double xi = x[a] - plane.position;
        if (std::abs(xi) >= D * (1 - 1e-9)) continue;  // not a first node (x₁ is within Δ)
        // With a node on the plane (|ξ| ≈ 0), its neighbours at ±Δ are second nodes.
        const double frac = plane.position / D - offset[a];
        const bool on_grid = std::abs(frac - std::round(frac)) < 1e-9;
        if (on_grid && std::abs(xi) > 1e-9 * D) continue;
        if (!plane.solid(x[first_in_plane], x[second_in_plane])) continue;
        Node n{f.index(i, j, k), 0, 0.0};
        if (!on_grid) {
          const int step = xi > 0 ? 1 : -1;  // x₂ away from the plane
          int i2 = i, j2 = j, k2 = k;
          (a == 0 ? i2 : a == 1 ? j2 : k2) += step;
          n.second = f.index(i2, j2, k2);  // x, y: the periodic halo; z: the slab halo
          const double d1 = std::abs(xi);
          n.factor = d1 / (d1 + D);
        } else {
          n.second = n.first;
        }
        out.push_back(n);
      }
  }
  return out;
}

template <grid::Location L>
double force(const std::vector<Node>& nodes, double dt, double g, const grid::Field<L>& uh, grid::Field<L>& f) {
  const double* u = uh.data();
  double* out = f.data();
  const double dg = dt * g;
  double sum = 0;
  for (const Node& n : nodes) {
    const double F = (n.factor * (u[n.second] + dg) - (u[n.first] + dg)) / dt;  // eq 4 with V_b = 0
    out[n.first] += F;
    sum += F;
  }
  return sum;
}
}  // namespace

struct PlaneForcingNodes {  // declared in the header
  std::vector<Node> c[3];
};

PlaneForcing::PlaneForcing(const grid::Slabs& slabs, RigidPlane plane) : slabs_(slabs), plane_(std::move(plane)) {
  const grid::Grid& g = slabs.grid();
  if (plane_.axis < 0 || plane_.axis > 2) {
    std::ostringstream m;
    m << "rigid plane: axis = " << plane_.axis << " must be 0 (x), 1 (y) or 2 (z)";
    throw InputError(m.str());
  }
  const double length[3] = {g.lx(), g.ly(), g.lz()};
  const double lo = plane_.axis == 2 ? 2 * g.dz() : 0.0, hi = length[plane_.axis] - lo;
  if (!(plane_.position > lo && plane_.position < hi)) {
    std::ostringstream m;
    m << "rigid plane: position = " << plane_.position << " along axis " << plane_.axis << " is outside (" << lo << ", "
      << hi << ")" << (plane_.axis == 2 ? " (two cells off the z walls: x2 must be a fluid node)" : "");
    throw InputError(m.str());
  }
  if (!plane_.solid) throw InputError("rigid plane: no solid(a, b) predicate given");
  grid::XFaceField u(slabs);
  grid::YFaceField v(slabs);
  grid::ZFaceField w(slabs);
  auto nodes = std::make_shared<PlaneForcingNodes>();
  nodes->c[0] = forced_nodes_of(slabs, plane_, u);
  nodes->c[1] = forced_nodes_of(slabs, plane_, v);
  nodes->c[2] = forced_nodes_of(slabs, plane_, w);
  nodes_ = std::move(nodes);
}

Vec3 PlaneForcing::apply(double dt, const ConstVelocityView& u_hat, VelocityView f, const Vec3& g) const {
  double local[3] = {0, 0, 0}, global[3] = {0, 0, 0};
  if (active_) {
    local[0] = force(nodes_->c[0], dt, g.x(), u_hat.u, f.u);
    local[1] = force(nodes_->c[1], dt, g.y(), u_hat.v, f.v);
    local[2] = force(nodes_->c[2], dt, g.z(), u_hat.w, f.w);
  }
  MPI_Allreduce(local, global, 3, MPI_DOUBLE, MPI_SUM, slabs_.comm());
  return Vec3(global[0], global[1], global[2]) * slabs_.grid().cell_volume();
}

std::array<std::size_t, 3> PlaneForcing::forced_nodes() const {
  return {nodes_->c[0].size(), nodes_->c[1].size(), nodes_->c[2].size()};
}

}  // namespace systole::ibm
