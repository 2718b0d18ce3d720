#include "solver/grid/grid.h"

#include <cmath>
#include <cstring>
#include <sstream>
#include <stdexcept>
#include <string>

#include "solver/core/errors.h"

namespace systole::grid {

const char* to_string(Location location) {
  switch (location) {
    case Location::cell: return "cell centre";
    case Location::x_face: return "x-face";
    case Location::y_face: return "y-face";
    case Location::z_face: return "z-face";
  }
  return "?";
}

namespace {
void require_cells(const char* name, int n) {
  if (n < 2) {
    std::ostringstream m;
    m << "grid." << name << " = " << n << " is out of range [2, 2^20] (cells)";
    throw InputError(m.str());
  }
}
void require_length(const char* name, double l) {
  if (!(l > 0) || !std::isfinite(l)) {
    std::ostringstream m;
    m << "grid." << name << " = " << l << " must be a positive finite length (nondimensional)";
    throw InputError(m.str());
  }
}
}  // namespace

Grid::Grid(const BoxSpec& spec) : spec_(spec) {
  require_cells("nx", spec.nx);
  require_cells("ny", spec.ny);
  require_cells("nz", spec.nz);
  require_length("lx", spec.lx);
  require_length("ly", spec.ly);
  require_length("lz", spec.lz);
}

Range block_range(int n, int parts, int p) {
  const int base = n / parts, extra = n % parts;
  return {p * base + (p < extra ? p : extra), base + (p < extra ? 1 : 0)};
}

std::vector<Range> weighted_ranges(const std::vector<double>& weights, int parts) {
  const int n = static_cast<int>(weights.size());
  if (parts < 1 || n < parts)
    throw std::invalid_argument("weighted_ranges: " + std::to_string(n) + " items cannot be split into " +
                                std::to_string(parts) + " non-empty parts");
  std::vector<double> prefix(static_cast<std::size_t>(n) + 1, 0.0);
  for (int i = 0; i < n; ++i) {
    const double w = weights[static_cast<std::size_t>(i)];
    if (!(w >= 0) || !std::isfinite(w))
      throw std::invalid_argument("weighted_ranges: weight " + std::to_string(i) + " = " + std::to_string(w) +
                                  " must be finite and >= 0");
    prefix[static_cast<std::size_t>(i) + 1] = prefix[static_cast<std::size_t>(i)] + w;
  }
  const double total = prefix.back();
  if (!(total > 0)) throw std::invalid_argument("weighted_ranges: the weights' total must be > 0");
  std::vector<Range> out(static_cast<std::size_t>(parts));
  int begin = 0;
  for (int p = 0; p < parts; ++p) {
    int end = n;
    if (p + 1 < parts) {
      const double target = total * (p + 1) / parts;
      // [begin + 1, n - (parts - p - 1)]: this part and every later one keep an item
      end = begin + 1;
      for (int b = begin + 2; b <= n - (parts - p - 1); ++b)
        if (std::abs(prefix[static_cast<std::size_t>(b)] - target) < std::abs(prefix[static_cast<std::size_t>(end)] - target))
          end = b;
    }
    out[static_cast<std::size_t>(p)] = {begin, end - begin};
    begin = end;
  }
  return out;
}

Slabs::Slabs(const Grid& grid, MPI_Comm comm, const std::vector<double>& plane_weights) : grid_(grid) {
  MPI_Comm_dup(comm, &comm_);
  MPI_Comm_rank(comm_, &rank_);
  MPI_Comm_size(comm_, &size_);
  if (grid.nz() < size_ || grid.ny() < size_) {
    MPI_Comm_free(&comm_);
    std::ostringstream m;
    m << "grid: nz = " << grid.nz() << " and ny = " << grid.ny() << " must each be at least the "
      << "number of MPI ranks (" << size_ << "): every rank owns a z-slab and a y-slab";
    throw InputError(m.str());
  }
  if (!plane_weights.empty() && static_cast<int>(plane_weights.size()) != grid.nz()) {
    MPI_Comm_free(&comm_);
    throw std::invalid_argument("grid: " + std::to_string(plane_weights.size()) + " plane weights for nz = " +
                                std::to_string(grid.nz()) + " planes");
  }
  try {
    if (plane_weights.empty())
      for (int r = 0; r < size_; ++r) z_ranges_.push_back(block_range(grid.nz(), size_, r));
    else
      z_ranges_ = weighted_ranges(plane_weights, size_);
  } catch (...) {
    MPI_Comm_free(&comm_);
    throw;
  }
  z_ = z_ranges_[static_cast<std::size_t>(rank_)];
}

Slabs::~Slabs() {
  int finalized = 0;
  MPI_Finalized(&finalized);
  if (comm_ != MPI_COMM_NULL && !finalized) MPI_Comm_free(&comm_);
}

void fill_periodic_xy(double* data, int nx, int ny, int k_count) {
  const std::ptrdiff_t sx = nx + 2, sxy = sx * (ny + 2);
  for (int k = -1; k <= k_count; ++k) {
    double* p = data + sxy * (k + 1);
    for (int j = 0; j < ny; ++j) {
      double* row = p + sx * (j + 1);
      row[0] = row[nx];       // i = -1  ← i = nx-1
      row[nx + 1] = row[1];   // i = nx  ← i = 0
    }
    std::memcpy(p, p + sx * ny, sizeof(double) * sx);              // j = -1 ← j = ny-1
    std::memcpy(p + sx * (ny + 1), p + sx, sizeof(double) * sx);   // j = ny ← j = 0
  }
}

void exchange_halos(double* data, int nx, int ny, int k_count, const Slabs& slabs) {
  const std::ptrdiff_t sxy = static_cast<std::ptrdiff_t>(nx + 2) * (ny + 2);
  const int count = static_cast<int>(sxy);
  if (slabs.size() > 1) {
    double* first = data + sxy * 1;              // local k = 0
    double* last = data + sxy * k_count;         // local k = k_count-1
    double* halo_below = data;                   // local k = -1
    double* halo_above = data + sxy * (k_count + 1);
    // Upward: my last plane → the halo below of the rank above.
    MPI_Sendrecv(last, count, MPI_DOUBLE, slabs.rank_above(), 11, halo_below, count, MPI_DOUBLE,
                 slabs.rank_below(), 11, slabs.comm(), MPI_STATUS_IGNORE);
    MPI_Sendrecv(first, count, MPI_DOUBLE, slabs.rank_below(), 12, halo_above, count, MPI_DOUBLE,
                 slabs.rank_above(), 12, slabs.comm(), MPI_STATUS_IGNORE);
  }
  fill_periodic_xy(data, nx, ny, k_count);
}

}  // namespace systole::grid
