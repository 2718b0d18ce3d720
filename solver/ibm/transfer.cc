#include "solver/ibm/transfer.h"

#include <mpi.h>
#include <omp.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "solver/core/errors.h"

namespace systole::ibm {

using grid::Location;

Transfer::Transfer(const grid::Slabs& slabs, const Markers& markers, TransferKernel kernel)
    : slabs_(slabs), markers_(markers), kernel_(kernel) {
  rebuild_all();
}

bool Transfer::owns_plane(int k) const {
  // Centres outside the fluid (cannot happen for markers kept >= Δz off the walls) go to the
  // wall's rank.
  k = std::clamp(k, 0, slabs_.grid().nz() - 1);
  return k >= slabs_.k_begin() && k < slabs_.k_begin() + slabs_.k_count();
}

void Transfer::rebuild_all() {
  built_count_.assign(built_count_.size(), static_cast<std::size_t>(-1));  // "never built"
  (void)rebuild();
}

int Transfer::rebuild() {
  const std::vector<Body>& bodies = markers_.bodies();
  const MarkerArrays& m = markers_.markers();
  entries_.resize(bodies.size());
  built_active_.resize(bodies.size(), 0);
  built_first_.resize(bodies.size(), 0);
  built_count_.resize(bodies.size(), static_cast<std::size_t>(-1));
  built_position_.resize(m.size(), Vec3::Zero());
  int rebuilt = 0;
  for (std::size_t body = 0; body < bodies.size(); ++body) {
    const Body& b = bodies[body];
    const auto first = static_cast<std::ptrdiff_t>(b.first_marker), last = first + static_cast<std::ptrdiff_t>(b.marker_count);
    bool unchanged = built_count_[body] == b.marker_count && built_first_[body] == b.first_marker &&
                     built_active_[body] == static_cast<char>(b.active);
    if (unchanged && rebuild_tolerance_ > 0) {
      const double tol2 = rebuild_tolerance_ * rebuild_tolerance_;
      for (auto q = first; q < last && unchanged; ++q)
        unchanged = (m.position[static_cast<std::size_t>(q)] - built_position_[static_cast<std::size_t>(q)]).squaredNorm() <= tol2;
    } else if (unchanged) {
      unchanged = std::equal(m.position.begin() + first, m.position.begin() + last, built_position_.begin() + first);
    }
    if (unchanged) continue;
    rebuild_body(body);
    std::copy(m.position.begin() + first, m.position.begin() + last, built_position_.begin() + first);
    built_active_[body] = static_cast<char>(b.active);
    built_first_[body] = b.first_marker;
    built_count_[body] = b.marker_count;
    ++rebuilt;
  }
  return rebuilt;
}

void Transfer::set_rebuild_tolerance(double distance) {
  if (!(distance >= 0)) throw InputError("ibm: rebuild tolerance " + std::to_string(distance) + " must be >= 0");
  rebuild_tolerance_ = distance;
}

void Transfer::rebuild_body(std::size_t body) {
  const grid::Grid& g = slabs_.grid();
  const MarkerArrays& m = markers_.markers();
  const Body& b = markers_.bodies()[body];
  BodyEntries& E = entries_[body];
  for (auto& list : E.mls) list.clear();
  for (auto& list : E.tensor) list.clear();
  if (!b.active) return;
  const int lo = slabs_.k_begin(), hi = slabs_.k_begin() + slabs_.k_count();  // [lo, hi)
  const std::size_t first = b.first_marker, count = b.marker_count;
  // A marker that moved within a cell of a z wall (the MLS support would leave the fluid):
  // every rank holds every position, so every rank throws here alike (no rank left waiting in
  // a collective).
  {
    const double z_lo = g.dz(), z_hi = g.lz() - g.dz();
    for (std::size_t q = first; q < first + count; ++q)
      if (!(m.position[q].z() >= z_lo && m.position[q].z() <= z_hi)) throw WallProximityError(m.position[q]);
  }
  // Pass 1 (cheap): which (marker, component) pairs this rank needs, from the centre plane of
  // each support alone (the stencil's k_centre: mls_nearest, as in mls.cc), and each pair's
  // slot: the lists stay in marker order whatever the thread count.
  std::vector<std::uint32_t>& slot = slot_;    // kept between calls: no page faults per step
  std::vector<std::uint8_t>& flags = flags_;   // bit 2c: owner, bit 2c+1: spreads
  slot.resize(3 * count);
  flags.assign(count, 0);
  std::size_t n_c[3] = {0, 0, 0};
  for (std::size_t q = 0; q < count; ++q) {
    const double zc = m.position[first + q].z() / g.dz();
    for (int c = 0; c < 3; ++c) {
      const int kc = mls_nearest(zc - (c == 2 ? 0.0 : 0.5));
      const bool owner = owns_plane(kc), spreads = kc + 1 >= lo && kc - 1 < hi;
      if (!(owner || spreads)) continue;
      flags[q] = static_cast<std::uint8_t>(flags[q] | (owner ? 1 << (2 * c) : 0) | (spreads ? 2 << (2 * c) : 0));
      slot[3 * q + static_cast<std::size_t>(c)] = static_cast<std::uint32_t>(n_c[c]++);
    }
  }
  // Pass 2: the stencils (the three faces share their 1-D weights), each into its slot.
  auto fill = [&](auto& lists, auto stencils) {
    for (int c = 0; c < 3; ++c) lists[static_cast<std::size_t>(c)].resize(n_c[c]);
    parallel_for_rethrow(static_cast<std::ptrdiff_t>(count), kThreadedMarkers, [&](std::ptrdiff_t qq) {
      const std::size_t q = static_cast<std::size_t>(qq);
      if (flags[q] == 0) return;
      decltype(stencils) st;
      if constexpr (std::is_same_v<decltype(stencils), std::array<TensorStencil, 3>>)
        divergence_free_face_stencils(g, m.position[first + q], st);
      else
        mls_face_stencils(g, m.position[first + q], st);
      for (int c = 0; c < 3; ++c) {
        const bool owner = (flags[q] >> (2 * c)) & 1, spreads = (flags[q] >> (2 * c + 1)) & 1;
        if (!(owner || spreads)) continue;
        auto& e = lists[static_cast<std::size_t>(c)][slot[3 * q + static_cast<std::size_t>(c)]];
        e.marker = static_cast<std::uint32_t>(first + q);
        e.owner = owner;
        e.spreads = spreads;
        e.stencil = st[static_cast<std::size_t>(c)];
      }
    });
  };
  if (kernel_ == TransferKernel::divergence_free)
    fill(E.tensor, std::array<TensorStencil, 3>{});
  else
    fill(E.mls, std::array<MlsStencil, 3>{});
}

template <class Stencil>
void Transfer::interpolate_entries(const std::vector<Entry<Stencil>>& entries, const auto& f, int c,
                                   std::vector<Vec3>& out) const {
  // Each entry writes its own marker's slot: no races.
#pragma omp parallel for schedule(static) if (static_cast<std::ptrdiff_t>(entries.size()) >= kThreadedMarkers)
  for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(entries.size()); ++q) {
    const Entry<Stencil>& e = entries[static_cast<std::size_t>(q)];
    if (!e.owner) continue;
    if constexpr (std::is_same_v<Stencil, TensorStencil>)
      out[e.marker][c] = apply_stencil(f, e.stencil);
    else
      out[e.marker][c] = apply_stencil(f, e.stencil, e.stencil.phi);
  }
}

template <grid::Location L>
void Transfer::interpolate_component(const grid::Field<L>& f, int c, std::vector<Vec3>& out) const {
  const auto k = static_cast<std::size_t>(c);
  for (const BodyEntries& body : entries_) {
    interpolate_entries(body.mls[k], f, c, out);
    interpolate_entries(body.tensor[k], f, c, out);
  }
}

std::vector<Vec3> Transfer::interpolate(const ConstVelocityView& u) const {
  std::vector<Vec3> out;
  interpolate(u, out);
  return out;
}

void Transfer::interpolate(const ConstVelocityView& u, std::vector<Vec3>& out) const {
  const std::size_t n = markers_.size();
  out.assign(n, Vec3::Zero());
  interpolate_component(u.u, 0, out);
  interpolate_component(u.v, 1, out);
  interpolate_component(u.w, 2, out);
  // Exactly one rank contributes each non-zero value: the sum is the one-rank value bitwise.
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "Vec3 must be three contiguous doubles");
  if (slabs_.size() > 1)
    MPI_Allreduce(MPI_IN_PLACE, out.data()->data(), static_cast<int>(3 * n), MPI_DOUBLE, MPI_SUM, slabs_.comm());
}

namespace {

// f += amplitude φ on this rank's planes [kb, kb + nzl) of a stencil's support.
template <grid::Location L>
void add_stencil(grid::Field<L>& f, const MlsStencil& s, double amplitude) {
  const int kb = f.k_begin(), nzl = f.k_count();
  const SupportOffsets o(f, s.i0, s.j0);
  const std::ptrdiff_t *ii = o.i, *jj = o.j;
  double* base = f.data() + f.index(0, 0, 0);
  for (int cc = s.c_begin; cc < s.c_end; ++cc) {
    const int k = s.k0 + cc - kb;
    if (k < 0 || k >= nzl) continue;  // another rank's plane
    double* plane = base + k * f.stride_k();
    for (int b = 0; b < 3; ++b) {
      double* row = plane + jj[b];
      const double* phi = s.phi.data() + 3 * b + 9 * cc;
      row[ii[0]] += amplitude * phi[0];
      row[ii[1]] += amplitude * phi[1];
      row[ii[2]] += amplitude * phi[2];
    }
  }
}

template <grid::Location L>
void add_stencil(grid::Field<L>& f, const TensorStencil& s, double amplitude) {
  const int kb = f.k_begin(), nzl = f.k_count();
  const SupportOffsets o(f, s.i0, s.j0);
  const std::ptrdiff_t *ii = o.i, *jj = o.j;
  double* base = f.data() + f.index(0, 0, 0);
  for (int cc = s.c_begin; cc < s.c_end; ++cc) {
    const int k = s.k0 + cc - kb;
    const double zc = s.z[static_cast<std::size_t>(cc)];
    if (k < 0 || k >= nzl || zc == 0) continue;  // another rank's plane, or no weight
    double* plane = base + k * f.stride_k();
    for (int b = 0; b < 3; ++b) {
      const double yb = s.y[static_cast<std::size_t>(b)];
      if (yb == 0) continue;
      double* row = plane + jj[b];
      const double a_zy = amplitude * zc * yb;
      row[ii[0]] += a_zy * s.x[0];
      row[ii[1]] += a_zy * s.x[1];
      row[ii[2]] += a_zy * s.x[2];
    }
  }
}

}  // namespace

template <grid::Location L>
void Transfer::spread_component(int c, const std::vector<Vec3>& F, grid::Field<L>& f) const {
  const double cell_volume = slabs_.grid().cell_volume(), h = markers_.h();
  const std::vector<double>& area = markers_.markers().area;
  const auto k = static_cast<std::size_t>(c);
  auto spread_entries = [&](const auto& entries) {
    for (const auto& e : entries) {
      if (!e.spreads) continue;
      const double amplitude = area[e.marker] * h / cell_volume * F[e.marker][c];  // ς_b F_b
      if (amplitude == 0) continue;
      add_stencil(f, e.stencil, amplitude);
    }
  };
  for (const BodyEntries& body : entries_) {
    spread_entries(body.mls[k]);
    spread_entries(body.tensor[k]);
  }
}

void Transfer::spread(const std::vector<Vec3>& force_density, VelocityView f) const {
  // One thread per component: each writes only its own field, in marker order (race-free and
  // bitwise independent of the thread count).
#pragma omp parallel for schedule(static, 1) if (static_cast<std::ptrdiff_t>(markers_.size()) >= kThreadedMarkers)
  for (int c = 0; c < 3; ++c) {
    if (c == 0) spread_component(0, force_density, f.u);
    if (c == 1) spread_component(1, force_density, f.v);
    if (c == 2) spread_component(2, force_density, f.w);
  }
}

}  // namespace systole::ibm
