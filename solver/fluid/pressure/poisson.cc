#include "solver/fluid/pressure/poisson.h"

#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/fluid/operators.h"

namespace systole::fluid {

namespace {
int largest_prime_factor(int n) {
  int largest = 1;
  for (int p = 2; p * p <= n; ++p)
    while (n % p == 0) {
      largest = p;
      n /= p;
    }
  return std::max(largest, n);
}
std::ptrdiff_t round_up(std::ptrdiff_t n, std::ptrdiff_t multiple) {
  return (n + multiple - 1) / multiple * multiple;
}
// A reproducible noise value in [-0.5, 0.5) from a global index (independent of the ranks).
double noise(std::uint64_t index) {
  std::uint64_t z = index + 0x9E3779B97F4A7C15ull;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  z ^= z >> 31;
  return static_cast<double>(z >> 11) * 0x1.0p-53 - 0.5;
}
}  // namespace

PoissonSolver::PoissonSolver(const grid::Slabs& slabs, const PoissonSpec& spec) : slabs_(slabs) {
  if (spec.bottom_wall != WallPressureCondition::neumann || spec.top_wall != WallPressureCondition::neumann)
    throw InputError(
        "pressure.bottom_wall/top_wall = dirichlet is not supported; known: neumann (the "
        "projection needs dphi/dn = 0 where the wall-normal velocity is prescribed)");
  if (!(spec.self_test_relative_tolerance > 0 && spec.self_test_relative_tolerance < 1))
    throw InputError("pressure.self_test_relative_tolerance = " +
                     std::to_string(spec.self_test_relative_tolerance) + " is out of range (0, 1)");
  const grid::Grid& g = slabs.grid();
  nx_ = g.nx();
  ny_ = g.ny();
  nz_ = g.nz();
  nxh_ = nx_ / 2 + 1;
  nzl_ = slabs.k_count();
  nyl_ = slabs.y_range(slabs.rank()).count;
  j_begin_ = slabs.y_range(slabs.rank()).begin;
  for (auto [name, n] : {std::pair{"nx", nx_}, std::pair{"ny", ny_}})
    if (largest_prime_factor(n) > 7) {
      std::ostringstream m;
      m << "grid." << name << " = " << n << " has the prime factor " << largest_prime_factor(n)
        << " > 7: the FFT works but is slow; prefer 2^a 3^b 5^c 7^d cells";
      warnings_.push_back(m.str());
    }

  real_plane_ = round_up(static_cast<std::ptrdiff_t>(nx_) * ny_, 8);
  complex_plane_ = round_up(static_cast<std::ptrdiff_t>(nxh_) * ny_, 4);
  real_ = fftw_alloc_real(static_cast<std::size_t>(real_plane_) * nzl_);
  spec_z_ = fftw_alloc_complex(static_cast<std::size_t>(complex_plane_) * nzl_);
  std::memset(real_, 0, sizeof(double) * real_plane_ * nzl_);
  std::memset(spec_z_, 0, sizeof(fftw_complex) * complex_plane_ * nzl_);
  // One plane's plan, executed plane by plane with the new-array interface: every rank uses
  // the same algorithm on every plane, so results do not depend on the decomposition.
  forward_ = fftw_plan_dft_r2c_2d(ny_, nx_, real_, spec_z_, FFTW_ESTIMATE);
  backward_ = fftw_plan_dft_c2r_2d(ny_, nx_, spec_z_, real_, FFTW_ESTIMATE);
  if (!forward_ || !backward_) throw InputError("pressure: FFTW could not plan nx×ny = " +
                                                std::to_string(nx_) + "×" + std::to_string(ny_));

  const int p = slabs.size();
  counts_send_.resize(p);
  displs_send_.resize(p);
  counts_recv_.resize(p);
  displs_recv_.resize(p);
  int offset_send = 0, offset_recv = 0;
  for (int r = 0; r < p; ++r) {
    counts_send_[r] = 2 * nzl_ * slabs.y_range(r).count * nxh_;
    counts_recv_[r] = 2 * slabs.z_range(r).count * nyl_ * nxh_;
    displs_send_[r] = offset_send;
    displs_recv_[r] = offset_recv;
    offset_send += counts_send_[r];
    offset_recv += counts_recv_[r];
  }
  send_.assign(offset_send, 0.0);
  recv_.assign(offset_recv, 0.0);
  spec_y_.assign(2ull * nyl_ * nz_ * nxh_, 0.0);
  work_.assign(static_cast<std::size_t>(nz_) * nxh_, 0.0);

  lambda_x_.resize(nxh_);
  lambda_y_.resize(ny_);
  const double pi = std::numbers::pi;
  for (int m = 0; m < nxh_; ++m) {
    const double s = std::sin(pi * m / nx_);
    lambda_x_[m] = -4.0 * s * s / (g.dx() * g.dx());
  }
  for (int m = 0; m < ny_; ++m) {
    const double s = std::sin(pi * m / ny_);
    lambda_y_[m] = -4.0 * s * s / (g.dy() * g.dy());
  }
  run_self_test(spec);
}

PoissonSolver::~PoissonSolver() {
  if (forward_) fftw_destroy_plan(forward_);
  if (backward_) fftw_destroy_plan(backward_);
  fftw_free(real_);
  fftw_free(spec_z_);
}

std::size_t PoissonSolver::bytes_allocated() const {
  return sizeof(double) * (real_plane_ * nzl_ + 2 * complex_plane_ * nzl_ + send_.size() + recv_.size() +
                           spec_y_.size() + work_.size());
}

void PoissonSolver::forward_transpose() {
  const int p = slabs_.size();
  for (int r = 0; r < p; ++r) {
    const grid::Range yr = slabs_.y_range(r);
    double* out = send_.data() + displs_send_[r];
    for (int k = 0; k < nzl_; ++k)
      for (int j = yr.begin; j < yr.begin + yr.count; ++j) {
        const double* in = reinterpret_cast<const double*>(spec_z_ + complex_plane_ * k + static_cast<std::ptrdiff_t>(j) * nxh_);
        std::memcpy(out, in, sizeof(double) * 2 * nxh_);
        out += 2 * nxh_;
      }
  }
  MPI_Alltoallv(send_.data(), counts_send_.data(), displs_send_.data(), MPI_DOUBLE, recv_.data(),
                counts_recv_.data(), displs_recv_.data(), MPI_DOUBLE, slabs_.comm());
  for (int s = 0; s < p; ++s) {
    const grid::Range zr = slabs_.z_range(s);
    const double* in = recv_.data() + displs_recv_[s];
    for (int k = zr.begin; k < zr.begin + zr.count; ++k)
      for (int j = 0; j < nyl_; ++j) {
        std::memcpy(spec_y_.data() + 2 * (static_cast<std::ptrdiff_t>(j) * nz_ + k) * nxh_, in,
                    sizeof(double) * 2 * nxh_);
        in += 2 * nxh_;
      }
  }
}

void PoissonSolver::backward_transpose() {
  const int p = slabs_.size();
  // Reverse roles: what was received is sent back, into the send layout.
  for (int s = 0; s < p; ++s) {
    const grid::Range zr = slabs_.z_range(s);
    double* out = recv_.data() + displs_recv_[s];
    for (int k = zr.begin; k < zr.begin + zr.count; ++k)
      for (int j = 0; j < nyl_; ++j) {
        std::memcpy(out, spec_y_.data() + 2 * (static_cast<std::ptrdiff_t>(j) * nz_ + k) * nxh_,
                    sizeof(double) * 2 * nxh_);
        out += 2 * nxh_;
      }
  }
  MPI_Alltoallv(recv_.data(), counts_recv_.data(), displs_recv_.data(), MPI_DOUBLE, send_.data(),
                counts_send_.data(), displs_send_.data(), MPI_DOUBLE, slabs_.comm());
  for (int r = 0; r < p; ++r) {
    const grid::Range yr = slabs_.y_range(r);
    const double* in = send_.data() + displs_send_[r];
    for (int k = 0; k < nzl_; ++k)
      for (int j = yr.begin; j < yr.begin + yr.count; ++j) {
        std::memcpy(reinterpret_cast<double*>(spec_z_ + complex_plane_ * k + static_cast<std::ptrdiff_t>(j) * nxh_),
                    in, sizeof(double) * 2 * nxh_);
        in += 2 * nxh_;
      }
  }
}

void PoissonSolver::solve_tridiagonal() {
  // Per (ky, kx): a φ_{k−1} + (λx + λy − 2a) φ_k + a φ_{k+1} = r_k, a = 1/Δz²; Neumann walls
  // (ghost = interior) add +a to the diagonal of the first and last rows.
  const double dz = slabs_.grid().dz();
  const double a = 1.0 / (dz * dz);
  const std::ptrdiff_t line = 2 * static_cast<std::ptrdiff_t>(nxh_);  // doubles per k row
  for (int jl = 0; jl < nyl_; ++jl) {
    const int jg = j_begin_ + jl;
    double* x = spec_y_.data() + static_cast<std::ptrdiff_t>(jl) * nz_ * line;  // [k][kx][re,im]
    double* cp = work_.data();                                                   // [k][kx]
    // Forward sweep.
    for (int k = 0; k < nz_; ++k) {
      const double edge = (k == 0 || k == nz_ - 1) ? a : 0.0;
      double* xk = x + k * line;
      double* ck = cp + static_cast<std::ptrdiff_t>(k) * nxh_;
      if (k == 0) {
        for (int m = 0; m < nxh_; ++m) {
          const double diag = lambda_x_[m] + lambda_y_[jg] - 2 * a + edge;
          const double inv = diag != 0 ? 1.0 / diag : 0.0;  // (0,0) mode: replaced below
          ck[m] = a * inv;
          xk[2 * m] *= inv;
          xk[2 * m + 1] *= inv;
        }
      } else {
        const double* xp = xk - line;
        const double* cpm = ck - nxh_;
        for (int m = 0; m < nxh_; ++m) {
          const double diag = lambda_x_[m] + lambda_y_[jg] - 2 * a + edge;
          const double inv = 1.0 / (diag - a * cpm[m]);
          ck[m] = a * inv;
          xk[2 * m] = (xk[2 * m] - a * xp[2 * m]) * inv;
          xk[2 * m + 1] = (xk[2 * m + 1] - a * xp[2 * m + 1]) * inv;
        }
      }
    }
    // Back substitution.
    for (int k = nz_ - 2; k >= 0; --k) {
      double* xk = x + k * line;
      const double* xn = xk + line;
      const double* ck = cp + static_cast<std::ptrdiff_t>(k) * nxh_;
      for (int m = 0; m < nxh_; ++m) {
        xk[2 * m] -= ck[m] * xn[2 * m];
        xk[2 * m + 1] -= ck[m] * xn[2 * m + 1];
      }
    }
    // The (0,0) mode (jg = 0, m = 0) is singular here; solve() overwrites it.
  }
}

void PoissonSolver::solve(const grid::CellField& rhs, grid::CellField& phi) {
  const double scale = 1.0 / (static_cast<double>(nx_) * ny_);
  for (int k = 0; k < nzl_; ++k) {
    double* plane = real_ + real_plane_ * k;
    for (int j = 0; j < ny_; ++j)
      std::memcpy(plane + static_cast<std::ptrdiff_t>(j) * nx_, rhs.data() + rhs.index(0, j, k), sizeof(double) * nx_);
    fftw_execute_dft_r2c(forward_, plane, spec_z_ + complex_plane_ * k);
  }
  forward_transpose();
  // Save the (0,0) mode's right-hand side (only the rank owning ky = 0 has it).
  std::vector<double> mean_rhs;
  if (j_begin_ == 0) {
    mean_rhs.resize(nz_);
    for (int k = 0; k < nz_; ++k) mean_rhs[k] = spec_y_[2 * static_cast<std::ptrdiff_t>(k) * nxh_];
  }
  solve_tridiagonal();
  if (j_begin_ == 0) {
    // (0,0) mode: a φ_{k−1} − 2a φ_k + a φ_{k+1} = r_k with Neumann rows at the ends is singular;
    // pin φ_0 = 0 and solve rows 1..nz−1 (Thomas). Imaginary part is zero.
    const double dz = slabs_.grid().dz();
    const double a = 1.0 / (dz * dz);
    std::vector<double> c(nz_, 0.0), d(nz_, 0.0);
    d[0] = 0;
    for (int k = 1; k < nz_; ++k) {
      const double diag = (k == nz_ - 1) ? -a : -2 * a;
      const double lower = (k == 1) ? 0.0 : a;  // φ_0 = 0 drops the coupling to row 0
      const double inv = 1.0 / (diag - lower * c[k - 1]);
      c[k] = a * inv;
      d[k] = (mean_rhs[k] - lower * d[k - 1]) * inv;
    }
    for (int k = nz_ - 2; k >= 1; --k) d[k] -= c[k] * d[k + 1];
    for (int k = 0; k < nz_; ++k) {
      spec_y_[2 * static_cast<std::ptrdiff_t>(k) * nxh_] = d[k];
      spec_y_[2 * static_cast<std::ptrdiff_t>(k) * nxh_ + 1] = 0.0;
    }
  }
  backward_transpose();
  for (int k = 0; k < nzl_; ++k) {
    double* plane = real_ + real_plane_ * k;
    fftw_execute_dft_c2r(backward_, spec_z_ + complex_plane_ * k, plane);
    for (int j = 0; j < ny_; ++j) {
      double* out = phi.data() + phi.index(0, j, k);
      const double* in = plane + static_cast<std::ptrdiff_t>(j) * nx_;
      for (int i = 0; i < nx_; ++i) out[i] = in[i] * scale;
    }
  }
}

void PoissonSolver::run_self_test(const PoissonSpec& spec) {
  const grid::Grid& g = slabs_.grid();
  grid::XFaceField u(slabs_);
  grid::YFaceField v(slabs_);
  grid::ZFaceField w(slabs_);
  grid::CellField div(slabs_), phi(slabs_);
  for (int k = 0; k < nzl_; ++k)
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i) {
        const std::uint64_t gi = (static_cast<std::uint64_t>(slabs_.k_begin() + k) * ny_ + j) * nx_ + i;
        u(i, j, k) = noise(3 * gi);
        v(i, j, k) = noise(3 * gi + 1);
        w(i, j, k) = (slabs_.k_begin() + k == 0) ? 0.0 : noise(3 * gi + 2);
      }
  grid::exchange_halos(u, slabs_);
  grid::exchange_halos(v, slabs_);
  grid::exchange_halos(w, slabs_);
  if (slabs_.owns_top_wall())
    for (int j = -1; j <= ny_; ++j)
      for (int i = -1; i <= nx_; ++i) w(i, j, nzl_) = 0.0;
  auto global_max = [&](double local) {
    double out = 0;
    MPI_Allreduce(&local, &out, 1, MPI_DOUBLE, MPI_MAX, slabs_.comm());
    return out;
  };
  const double before = global_max(max_abs_divergence_local(g, u, v, w));
  divergence_at_cell(g, u, v, w, 1.0, div);
  solve(div, phi);
  grid::exchange_halos(phi, slabs_);
  subtract_gradient_at_faces(slabs_, phi, 1.0, u, v, w);
  grid::exchange_halos(u, slabs_);
  grid::exchange_halos(v, slabs_);
  grid::exchange_halos(w, slabs_);
  if (slabs_.owns_top_wall())
    for (int j = -1; j <= ny_; ++j)
      for (int i = -1; i <= nx_; ++i) w(i, j, nzl_) = 0.0;
  const double after = global_max(max_abs_divergence_local(g, u, v, w));
  self_test_relative_divergence_ = after / before;
  if (!(self_test_relative_divergence_ <= spec.self_test_relative_tolerance)) {
    std::ostringstream m;
    m << "start-up self-test: projected noise keeps max|div u| / max|div u_0| = "
      << self_test_relative_divergence_ << " > " << spec.self_test_relative_tolerance;
    throw InstabilityError("fluid.pressure", "Poisson solver construction", 0.0, m.str());
  }
}

}  // namespace systole::fluid
