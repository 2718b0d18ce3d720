#pragma once
// Uniform staggered (MAC) grid on the box [0,Lx]×[0,Ly]×[0,Lz] (MODEL.md §3): periodic in x
// and y, walls at z = 0 and z = Lz. Lengths are nondimensional (d_m), see solver/grid/README.md.
//
// Index convention (global indices, cells i ∈ [0,nx), j ∈ [0,ny), k ∈ [0,nz)):
//   cell centre (i,j,k) at ((i+½)Δx, (j+½)Δy, (k+½)Δz)
//   x-face      (i,j,k) at ( i    Δx, (j+½)Δy, (k+½)Δz)   — the left face of cell i
//   y-face      (i,j,k) at ((i+½)Δx,  j    Δy, (k+½)Δz)
//   z-face      (i,j,k) at ((i+½)Δx, (j+½)Δy,  k    Δz)   — the bottom face of cell k;
//               z-face k = 0 is the bottom wall, z-face nz (top wall) is the top halo of the
//               last slab.
// Slab decomposition in z: rank r owns cells k ∈ [k_begin, k_begin + k_count) of every
// location (block distribution, the first nz % size ranks get one more). Every field stores
// one halo layer on each side in x, y and z.
#include <mpi.h>

#include <cstddef>
#include <string>
#include <vector>

namespace systole::grid {

enum class Location { cell, x_face, y_face, z_face };
const char* to_string(Location location);

// Box and resolution, nondimensional. Cells, not points: the seed's "129×129×145" grid (points,
// AFiD convention) is 128×128×144 cells.
struct BoxSpec {
  int nx = 0, ny = 0, nz = 0;           // cells
  double lx = 0, ly = 0, lz = 0;        // box lengths, nondimensional
};

// The global geometry. Valid from construction: throws InputError on non-positive or
// too-small sizes (nx, ny >= 2, nz >= 2, lengths > 0 and finite).
class Grid {
 public:
  explicit Grid(const BoxSpec& spec);
  int nx() const { return spec_.nx; }
  int ny() const { return spec_.ny; }
  int nz() const { return spec_.nz; }
  double lx() const { return spec_.lx; }
  double ly() const { return spec_.ly; }
  double lz() const { return spec_.lz; }
  double dx() const { return spec_.lx / spec_.nx; }
  double dy() const { return spec_.ly / spec_.ny; }
  double dz() const { return spec_.lz / spec_.nz; }
  double cell_volume() const { return dx() * dy() * dz(); }
  long long cells() const { return static_cast<long long>(spec_.nx) * spec_.ny * spec_.nz; }
  const BoxSpec& spec() const { return spec_; }
  // Coordinates of the point with global index i (j, k) of location L.
  double x(Location L, int i) const { return (i + (L == Location::x_face ? 0.0 : 0.5)) * dx(); }
  double y(Location L, int j) const { return (j + (L == Location::y_face ? 0.0 : 0.5)) * dy(); }
  double z(Location L, int k) const { return (k + (L == Location::z_face ? 0.0 : 0.5)) * dz(); }

 private:
  BoxSpec spec_;
};

// Block split of n items over `parts`: [begin, begin+count) of part p.
struct Range {
  int begin = 0, count = 0;
};
Range block_range(int n, int parts, int p);
// Contiguous split of weights.size() items over `parts` by weight (ours, for load balance): part
// p ends at the item boundary whose prefix sum is nearest to p/parts of the total (the first such
// boundary on a tie), every part keeping at least one item. Equal weights give block_range's
// counts up to where the remainder goes. Throws std::invalid_argument for fewer items than parts,
// a negative or non-finite weight, or a total that is not positive.
std::vector<Range> weighted_ranges(const std::vector<double>& weights, int parts);

// The slab decomposition in z of a Grid over an MPI communicator (duplicated: the slabs own a
// private communicator, freed on destruction). Also the y-slab split used by transposes.
// Throws InputError if a rank would own no z-slab or no y-slab (nz, ny < ranks).
// plane_weights (optional, nz entries, the same on every rank): the z planes are split by
// weighted_ranges instead of in equal blocks, e.g. by the work of the immersed bodies in each
// plane (a body's markers are worked on by the rank owning their planes).
class Slabs {
 public:
  Slabs(const Grid& grid, MPI_Comm comm, const std::vector<double>& plane_weights = {});
  ~Slabs();
  Slabs(const Slabs&) = delete;
  Slabs& operator=(const Slabs&) = delete;

  const Grid& grid() const { return grid_; }
  MPI_Comm comm() const { return comm_; }
  int rank() const { return rank_; }
  int size() const { return size_; }
  int k_begin() const { return z_.begin; }
  int k_count() const { return z_.count; }
  Range z_range(int rank) const { return z_ranges_.at(static_cast<std::size_t>(rank)); }
  Range y_range(int rank) const { return block_range(grid_.ny(), size_, rank); }
  bool owns_bottom_wall() const { return rank_ == 0; }
  bool owns_top_wall() const { return rank_ == size_ - 1; }
  int rank_below() const { return rank_ == 0 ? MPI_PROC_NULL : rank_ - 1; }
  int rank_above() const { return rank_ == size_ - 1 ? MPI_PROC_NULL : rank_ + 1; }

 private:
  Grid grid_;
  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  Range z_;
  std::vector<Range> z_ranges_;  // every rank's
};

// A field on this rank's slab with one halo layer each side; local indices i ∈ [-1, nx],
// j ∈ [-1, ny], k ∈ [-1, k_count] (k local: global k = k_begin + k). The location is part of
// the type: a pressure (Field<Location::cell>) cannot be passed where a u (x-face) is expected.
template <Location L>
class Field {
 public:
  static constexpr Location location = L;
  explicit Field(const Slabs& slabs)
      : nx_(slabs.grid().nx()), ny_(slabs.grid().ny()), nzl_(slabs.k_count()),
        k_begin_(slabs.k_begin()), sx_(nx_ + 2), sxy_(static_cast<std::ptrdiff_t>(nx_ + 2) * (ny_ + 2)),
        data_(static_cast<std::size_t>(sxy_) * (nzl_ + 2), 0.0) {}

  double& operator()(int i, int j, int k) { return data_[index(i, j, k)]; }
  double operator()(int i, int j, int k) const { return data_[index(i, j, k)]; }
  std::ptrdiff_t index(int i, int j, int k) const { return (i + 1) + sx_ * (j + 1) + sxy_ * (k + 1); }
  // Strides of the storage: +1 in i, +stride_j() in j, +stride_k() in k.
  std::ptrdiff_t stride_j() const { return sx_; }
  std::ptrdiff_t stride_k() const { return sxy_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  int k_count() const { return nzl_; }
  int k_begin() const { return k_begin_; }
  double* data() { return data_.data(); }
  const double* data() const { return data_.data(); }
  std::size_t size() const { return data_.size(); }
  std::size_t bytes() const { return data_.size() * sizeof(double); }
  void fill(double value) { data_.assign(data_.size(), value); }
  // A pointer to (0,0,k): the first interior point of local plane k.
  double* plane(int k) { return data_.data() + index(0, 0, k); }

 private:
  int nx_, ny_, nzl_, k_begin_;
  std::ptrdiff_t sx_, sxy_;
  std::vector<double> data_;
};

using CellField = Field<Location::cell>;
using XFaceField = Field<Location::x_face>;
using YFaceField = Field<Location::y_face>;
using ZFaceField = Field<Location::z_face>;

// Fills every halo that another rank or periodicity defines: first the z halos from the
// neighbouring slabs (MPI, collective on slabs.comm()), then the periodic x and y halos over
// the whole k range including z halos (so edges and corners are consistent). The z halos at
// the walls (below rank 0, above the last rank) are left untouched: boundary conditions are
// the caller's (solver/fluid).
void exchange_halos(double* data, int nx, int ny, int k_count, const Slabs& slabs);
template <Location L>
void exchange_halos(Field<L>& f, const Slabs& slabs) {
  exchange_halos(f.data(), f.nx(), f.ny(), f.k_count(), slabs);
}
// Periodic x and y halos only (no communication).
void fill_periodic_xy(double* data, int nx, int ny, int k_count);

}  // namespace systole::grid
