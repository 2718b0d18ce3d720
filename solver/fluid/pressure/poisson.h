#pragma once
// Direct solver of the pressure Poisson equation of the projection (MODEL.md §3, eq 9):
//   L φ = r,  L = the 7-point MAC Laplacian (= divergence ∘ gradient of solver/fluid/operators.h),
// periodic in x and y, homogeneous Neumann (∂φ/∂z = 0) at the walls z = 0, Lz.
// Method: FFTW real-to-complex transforms in x and y on each z-plane of the z-slab, a
// transpose to y-slabs (MPI_Alltoallv), one tridiagonal (Thomas) solve in z per wavenumber
// pair using the modified wavenumbers of the discrete operator, transpose back, inverse FFT.
// The (0,0) mode is singular (φ up to a constant): it is pinned by φ(kx=0,ky=0,z_0) = 0 (ours).
#include <fftw3.h>

#include <cstddef>
#include <string>
#include <vector>

#include "solver/grid/grid.h"

namespace systole::fluid {

enum class WallPressureCondition { neumann, dirichlet };

struct PoissonSpec {
  // The projection needs ∂φ/∂n = 0 where u·n is prescribed: only neumann is accepted.
  WallPressureCondition bottom_wall = WallPressureCondition::neumann;
  WallPressureCondition top_wall = WallPressureCondition::neumann;
  // Start-up self-test: max |div u| after projecting random noise, relative to max |div| before.
  double self_test_relative_tolerance = 1e-11;
};

class PoissonSolver {
 public:
  // Checks the boundary conditions (InputError), plans the transforms, runs the self-test
  // (InstabilityError "fluid.pressure" if it fails). Collective on slabs.comm(). Grid sizes
  // whose largest prime factor exceeds 7 are accepted with a warning (FFTW is slow on them).
  PoissonSolver(const grid::Slabs& slabs, const PoissonSpec& spec = {});
  ~PoissonSolver();
  PoissonSolver(const PoissonSolver&) = delete;
  PoissonSolver& operator=(const PoissonSolver&) = delete;

  // φ ← L⁻¹ r on the interior of φ (halos untouched); r is only read (its halos are not used).
  // For the pinned (0,0) mode, the part of r with non-zero mean is dropped. Collective.
  void solve(const grid::CellField& rhs, grid::CellField& phi);

  double self_test_relative_divergence() const { return self_test_relative_divergence_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  std::size_t bytes_allocated() const;

 private:
  void forward_transpose();   // spectral z-slabs → y-slabs
  void backward_transpose();  // y-slabs → z-slabs
  void solve_tridiagonal();   // on y-slabs
  void run_self_test(const PoissonSpec& spec);

  const grid::Slabs& slabs_;
  int nx_, ny_, nz_, nxh_, nzl_, nyl_, j_begin_;
  std::ptrdiff_t real_plane_, complex_plane_;  // padded plane strides (64-byte multiples)
  double* real_ = nullptr;                     // [k_local][ny][nx]
  fftw_complex* spec_z_ = nullptr;             // [k_local][ny][nxh]
  std::vector<double> send_, recv_;            // transpose buffers (complex as 2 doubles)
  std::vector<double> spec_y_;                 // [j_local][nz][nxh] complex
  std::vector<double> work_;                   // Thomas c' per [k][kx]
  std::vector<double> lambda_x_, lambda_y_;    // modified wavenumbers (eigenvalues of δ²)
  std::vector<int> counts_send_, displs_send_, counts_recv_, displs_recv_;
  fftw_plan forward_ = nullptr, backward_ = nullptr;
  double self_test_relative_divergence_ = 0;
  std::vector<std::string> warnings_;
};

}  // namespace systole::fluid
