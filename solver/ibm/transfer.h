#pragma once
// Interpolation and spreading between the markers and the staggered grid (MODEL.md §4, eq 5–7),
// distributed over the z-slabs of solver/grid.
//
// Who computes what (ours):
// - Interpolation of component c at marker b is done by the rank whose slab holds the centre
//   plane of b's support for c (the "owner"): its 3 planes lie in the slab plus its halo
//   planes, so the owner needs only halos that are already valid (the fluid hands û with valid
//   halos). The values are then summed over ranks (MPI_Allreduce): exactly one rank
//   contributes a non-zero, so every rank gets the np = 1 value bitwise.
// - Spreading: every rank adds the forcing of every marker whose support reaches its slab,
//   writing only its own interior nodes (markers are replicated, markers.h). No reverse halo
//   sum, no write conflicts, and each node accumulates its contributions in marker order on
//   any number of ranks: bitwise equal to np = 1.
// The stencils depend only on marker positions: rebuild() after the markers moved. rebuild()
// recomputes only the bodies whose marker positions or on/off state changed since the last
// build (ours, round 3: a fixed body, e.g. the valvular plane, keeps its stencils).
#include <array>
#include <cstdint>
#include <vector>

#include "solver/grid/grid.h"
#include "solver/ibm/markers.h"
#include "solver/ibm/mls.h"

namespace systole::ibm {

// The fluid's velocity as the immersed boundary sees it (no dependency on solver/fluid).
struct ConstVelocityView {
  const grid::XFaceField& u;
  const grid::YFaceField& v;
  const grid::ZFaceField& w;
};
struct VelocityView {
  grid::XFaceField& u;
  grid::YFaceField& v;
  grid::ZFaceField& w;
};

// Loops over fewer markers than this run on one thread (ours): a parallel region costs a
// fork/join and, on an oversubscribed machine, a time slice per barrier — measured: the Womersley
// CI case (5 334 markers) went from 8 s to 150 s wall with threads on every loop under load.
inline constexpr std::ptrdiff_t kThreadedMarkers = 20000;

// The markers' interpolation and spreading weights: the seed's MLS shape functions (eq 5), or
// the divergence-free composite B-spline kernel (ours, mls.h divergence_free_face_stencils).
enum class TransferKernel { mls, divergence_free };

class Transfer {
 public:
  // Builds the stencils of `markers`' active markers that this rank needs. Collective: no
  // (purely local), but every rank must call rebuild() at the same points.
  Transfer(const grid::Slabs& slabs, const Markers& markers, TransferKernel kernel = TransferKernel::mls);
  // Rebuilds the stencils of the bodies that moved (or were switched on/off, or gained
  // markers); returns how many bodies were rebuilt. rebuild_all() ignores the check.
  int rebuild();
  void rebuild_all();
  // A body counts as unmoved while no marker has moved more than `distance` (grid units) from
  // where its stencil was built (ours; default 0: any change rebuilds). The stale stencils then
  // serve both interpolation and spreading, so the spread force still sums to the Lagrangian
  // total; the error is O(distance · ∇u). Must be the same on every rank.
  void set_rebuild_tolerance(double distance);

  // u(X_b) for every marker (0 for inactive ones), the same on every rank. Collective.
  // Halos of u must be valid.
  std::vector<Vec3> interpolate(const ConstVelocityView& u) const;
  // The same into `out` (resized to the marker count; reusing its storage avoids the page
  // faults of a fresh allocation per call).
  void interpolate(const ConstVelocityView& u, std::vector<Vec3>& out) const;
  // Adds f_k += ς_b φ_k(X_b) F_b on this rank's interior faces, ς_b = ΔV_b / ΔV_cell
  // (eq 6–7; with Σφ_k = 1 the total grid force Σ f_k ΔV_cell equals Σ F_b ΔV_b). F is a
  // force density per marker (inactive markers skipped). Not collective.
  void spread(const std::vector<Vec3>& force_density, VelocityView f) const;

  // Interpolates a scalar field at arbitrary points with its location's stencils (ownership as
  // above). Collective.
  template <grid::Location L>
  std::vector<double> interpolate_points(const grid::Field<L>& field, const std::vector<Vec3>& points) const;

  const Markers& markers() const { return markers_; }
  const grid::Slabs& slabs() const { return slabs_; }
  TransferKernel kernel() const { return kernel_; }
  // Whether this rank owns the centre plane k (global) of a support.
  bool owns_plane(int k) const;

 private:
  double rebuild_tolerance_ = 0;
  template <class Stencil>
  struct Entry {
    std::uint32_t marker;
    bool owner;       // this rank interpolates it
    bool spreads;     // its support reaches this rank's interior planes
    Stencil stencil;
  };
  // Per body, per component (u, v, w): the entries of its markers this rank needs, in marker
  // order (bodies' markers are contiguous, so body order then entry order is marker order); the
  // kernel's in their 1-D factors (TensorStencil), MLS's as 27 weights.
  struct BodyEntries {
    std::array<std::vector<Entry<MlsStencil>>, 3> mls;
    std::array<std::vector<Entry<TensorStencil>>, 3> tensor;
  };
  void rebuild_body(std::size_t body);
  template <class Stencil>
  void interpolate_entries(const std::vector<Entry<Stencil>>& entries, const auto& f, int c, std::vector<Vec3>& out) const;
  template <grid::Location L>
  void interpolate_component(const grid::Field<L>& f, int c, std::vector<Vec3>& out) const;
  template <grid::Location L>
  void spread_component(int c, const std::vector<Vec3>& F, grid::Field<L>& f) const;
  const grid::Slabs& slabs_;
  const Markers& markers_;
  TransferKernel kernel_;
  std::vector<BodyEntries> entries_;
  // What the stencils were built from (to skip bodies that did not move).
  std::vector<Vec3> built_position_;
  std::vector<char> built_active_;
  std::vector<std::size_t> built_first_, built_count_;
  std::vector<std::uint32_t> slot_;  // rebuild scratch
  std::vector<std::uint8_t> flags_;
};

// A support's x offsets and y row offsets in a field's storage, periodic (i0, j0 in [0, n)).
struct SupportOffsets {
  std::ptrdiff_t i[3], j[3];
  template <grid::Location L>
  SupportOffsets(const grid::Field<L>& f, int i0, int j0) {
    for (int a = 0; a < 3; ++a) {
      const int x = i0 + a, y = j0 + a;
      i[a] = x >= f.nx() ? x - f.nx() : x;
      j[a] = (y >= f.ny() ? y - f.ny() : y) * f.stride_j();
    }
  }
};

// Value of a field from an MLS stencil on this rank (planes k0..k0+2 must be local or halo).
// Planes outside the fluid (φ = 0) are skipped; nodes are visited in the order c, b, a.
template <grid::Location L>
double apply_stencil(const grid::Field<L>& f, const MlsStencil& s, const std::array<double, 27>& weights) {
  const SupportOffsets o(f, s.i0, s.j0);
  const std::ptrdiff_t *ii = o.i, *jj = o.j;
  const double* base = f.data() + f.index(0, 0, s.k0 - f.k_begin());
  double sum = 0;
  for (int c = s.c_begin; c < s.c_end; ++c) {
    const double* plane = base + c * f.stride_k();
    for (int b = 0; b < 3; ++b) {
      const double* row = plane + jj[b];
      const double* w = weights.data() + 3 * b + 9 * c;
      sum += w[0] * row[ii[0]];
      sum += w[1] * row[ii[1]];
      sum += w[2] * row[ii[2]];
    }
  }
  return sum;
}

// The same from a tensor-product stencil, Σ_c z_c Σ_b y_b Σ_a x_a f (zero rows and planes
// skipped: the kernel's hat factors leave one of three).
template <grid::Location L>
double apply_stencil(const grid::Field<L>& f, const TensorStencil& s) {
  const SupportOffsets o(f, s.i0, s.j0);
  const std::ptrdiff_t *ii = o.i, *jj = o.j;
  const double* base = f.data() + f.index(0, 0, s.k0 - f.k_begin());
  double sum = 0;
  for (int c = s.c_begin; c < s.c_end; ++c) {
    const double zc = s.z[static_cast<std::size_t>(c)];
    if (zc == 0) continue;
    const double* plane = base + c * f.stride_k();
    double plane_sum = 0;
    for (int b = 0; b < 3; ++b) {
      const double yb = s.y[static_cast<std::size_t>(b)];
      if (yb == 0) continue;
      const double* row = plane + jj[b];
      plane_sum += yb * (s.x[0] * row[ii[0]] + s.x[1] * row[ii[1]] + s.x[2] * row[ii[2]]);
    }
    sum += zc * plane_sum;
  }
  return sum;
}

template <grid::Location L>
std::vector<double> Transfer::interpolate_points(const grid::Field<L>& field, const std::vector<Vec3>& points) const {
  std::vector<double> local(points.size(), 0.0), global(points.size(), 0.0);
  for (std::size_t p = 0; p < points.size(); ++p) {
    const MlsStencil s = mls_stencil(slabs_.grid(), L, points[p]);
    if (owns_plane(s.k_centre)) local[p] = apply_stencil(field, s, s.phi);
  }
  MPI_Allreduce(local.data(), global.data(), static_cast<int>(local.size()), MPI_DOUBLE, MPI_SUM, slabs_.comm());
  return global;
}

}  // namespace systole::ibm
