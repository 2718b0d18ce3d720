#include "solver/ibm/transfer.h"

#include <mpi.h>
#include <omp.h>

#include <algorithm>

namespace systole::ibm {

using grid::Location;

Transfer::Transfer(const grid::Slabs& slabs, const Markers& markers) : slabs_(slabs), markers_(markers) {
  rebuild();
}

bool Transfer::owns_plane(int k) const {
  // Centres outside the fluid (cannot happen for markers kept >= Δz off the walls) go to the
  // wall's rank.
  k = std::clamp(k, 0, slabs_.grid().nz() - 1);
  return k >= slabs_.k_begin() && k < slabs_.k_begin() + slabs_.k_count();
}

void Transfer::rebuild() {
  const grid::Grid& g = slabs_.grid();
  const MarkerArrays& m = markers_.markers();
  const int lo = slabs_.k_begin(), hi = slabs_.k_begin() + slabs_.k_count();  // [lo, hi)
  const Location where[3] = {Location::x_face, Location::y_face, Location::z_face};
  // Threads take contiguous blocks of markers in thread order (schedule(static), OpenMP 5.1
  // §2.11.4) and keep their own lists; concatenated in thread order they are in marker order —
  // the order spreading accumulates in, so the result does not depend on the thread count.
  const std::size_t n = m.size();
  const int nt = static_cast<std::ptrdiff_t>(n) >= kThreadedMarkers ? omp_get_max_threads() : 1;
  std::vector<std::array<std::vector<Entry>, 3>> parts(static_cast<std::size_t>(nt));
#pragma omp parallel num_threads(nt)
  {
    auto& mine = parts[static_cast<std::size_t>(omp_get_thread_num())];
    for (auto& list : mine) list.reserve(n / static_cast<std::size_t>(nt) + 1);  // one rank holds ≈ all
#pragma omp for schedule(static)
    for (std::ptrdiff_t bb = 0; bb < static_cast<std::ptrdiff_t>(n); ++bb) {
      const std::size_t b = static_cast<std::size_t>(bb);
      if (!markers_.active(b)) continue;
      for (int c = 0; c < 3; ++c) {
        // Cheap pre-check on the z extent before building the stencil (support: centre ± 1).
        const double off = where[c] == Location::z_face ? 0.0 : 0.5;
        const int kc = static_cast<int>(std::lround(m.position[b].z() / g.dz() - off));
        if (kc + 1 < lo - 1 || kc - 1 > hi) continue;
        Entry e{b, false, false, mls_stencil(g, where[c], m.position[b])};
        e.owner = owns_plane(e.stencil.k_centre);
        e.spreads = e.stencil.k0 + 2 >= lo && e.stencil.k0 < hi;
        if (e.owner || e.spreads) mine[c].push_back(e);
      }
    }
  }
  for (int c = 0; c < 3; ++c) {
    std::vector<Entry>& list = entries_[c];
    list.clear();
    std::size_t total = 0;
    for (const auto& part : parts) total += part[c].size();
    list.reserve(total);
    for (auto& part : parts) list.insert(list.end(), part[c].begin(), part[c].end());
  }
}

template <grid::Location L>
void Transfer::interpolate_component(const grid::Field<L>& f, const std::vector<Entry>& entries, int c,
                                     std::vector<double>& out) const {
  // Each entry writes its own marker's slot: no races.
#pragma omp parallel for schedule(static) if (static_cast<std::ptrdiff_t>(entries.size()) >= kThreadedMarkers)
  for (std::ptrdiff_t q = 0; q < static_cast<std::ptrdiff_t>(entries.size()); ++q) {
    const Entry& e = entries[static_cast<std::size_t>(q)];
    if (e.owner) out[3 * e.marker + c] = apply_stencil(f, e.stencil, e.stencil.phi);
  }
}

std::vector<Vec3> Transfer::interpolate(const ConstVelocityView& u) const {
  const std::size_t n = markers_.size();
  std::vector<double> local(3 * n, 0.0), global(3 * n, 0.0);
  interpolate_component(u.u, entries_[0], 0, local);
  interpolate_component(u.v, entries_[1], 1, local);
  interpolate_component(u.w, entries_[2], 2, local);
  MPI_Allreduce(local.data(), global.data(), static_cast<int>(3 * n), MPI_DOUBLE, MPI_SUM, slabs_.comm());
  std::vector<Vec3> out(n);
  for (std::size_t b = 0; b < n; ++b) out[b] = Vec3(global[3 * b], global[3 * b + 1], global[3 * b + 2]);
  return out;
}

template <grid::Location L>
void Transfer::spread_component(const std::vector<Entry>& entries, int c, const std::vector<Vec3>& F,
                                grid::Field<L>& f) const {
  const double cell_volume = slabs_.grid().cell_volume();
  const int nx = f.nx(), ny = f.ny(), kb = f.k_begin(), nzl = f.k_count();
  for (const Entry& e : entries) {
    if (!e.spreads) continue;
    const double amplitude = markers_.forcing_volume(e.marker) / cell_volume * F[e.marker][c];  // ς_b F_b
    if (amplitude == 0) continue;
    const MlsStencil& s = e.stencil;
    for (int cc = 0; cc < 3; ++cc) {
      const int k = s.k0 + cc - kb;
      if (k < 0 || k >= nzl) continue;  // another rank's plane (or outside the fluid: φ = 0)
      for (int b = 0; b < 3; ++b) {
        int j = s.j0 + b;
        if (j >= ny) j -= ny;
        for (int a = 0; a < 3; ++a) {
          const double phi = s.phi[a + 3 * b + 9 * cc];
          if (phi == 0) continue;
          int i = s.i0 + a;
          if (i >= nx) i -= nx;
          f(i, j, k) += amplitude * phi;
        }
      }
    }
  }
}

void Transfer::spread(const std::vector<Vec3>& force_density, VelocityView f) const {
  // One thread per component: each writes only its own field, in marker order (race-free and
  // bitwise independent of the thread count).
#pragma omp parallel for schedule(static, 1) if (static_cast<std::ptrdiff_t>(markers_.size()) >= kThreadedMarkers)
  for (int c = 0; c < 3; ++c) {
    if (c == 0) spread_component(entries_[0], 0, force_density, f.u);
    if (c == 1) spread_component(entries_[1], 1, force_density, f.v);
    if (c == 2) spread_component(entries_[2], 2, force_density, f.w);
  }
}

}  // namespace systole::ibm
