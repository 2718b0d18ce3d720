#pragma once
// Moving-least-squares (MLS) shape functions of the immersed boundary (MODEL.md §4, eq 5–7;
// Vanella & Balaras 2009 J. Comput. Phys. 228:6617; de Tullio & Pascazio 2016 JCP 325:201).
//
// For a point X and one staggered location L (a velocity component's faces, or cell centres
// for the pressure), the support is the 3×3×3 block of L-nodes centred on the node nearest
// to X. With the linear basis p(x) = [1, (x−X)/Δ] and weights W_k, the weighted least-squares
// fit of nodal values u_k gives
//     u(X) ≈ Σ_k φ_k u_k,   φ_k = p(X)ᵀ A⁻¹ W_k p(x_k),   A = Σ_k W_k p(x_k) p(x_k)ᵀ   (eq 5)
// so Σφ_k = 1 and Σφ_k x_k = X exactly (a linear field is reproduced to round-off).
// Closed form (ours, round 3, for cost; algebraically the same φ): the weight is a tensor
// product, so with per-direction normalised weights ŵ_d(a) = w_d(a)/Σw_d, means m_d = Σŵ_d δ_d
// and variances v_d = Σŵ_d δ_d² − m_d², the moment matrix is A = (Πℓ S⁰_ℓ)[[1, mᵀ], [m, mmᵀ + D]],
// D = diag(v), whose first column of the inverse is known (Schur complement of the 1-block):
//     φ_abc = ŵ_x(a) ŵ_y(b) ŵ_z(c) [1 − g_x(a) − g_y(b) − g_z(c)],   g_d(a) = m_d (δ_d(a) − m_d)/v_d,
// and ∂φ/∂X_d from the 1-D derivatives of ŵ_d and g_d. No 4×4 inverse; A is singular iff some
// v_d = 0 (fewer than two nodes of a direction in the fluid).
// Weight (ours; the paper names no kernel): W_k = Π_d w(|x_k,d − X_d| / (2Δ_d)) with the cubic
// B-spline w(r) = 2/3 − 4r² + 4r³ (r ≤ ½), 4/3 (1 − r)³ (½ < r ≤ 1): positive on all 27 nodes
// (r ≤ ¾), smooth, compact.
// Walls: nodes outside the fluid in z (cell levels k ∉ [0, nz); z-faces k ∉ [1, nz−1], the
// wall faces where w = 0 is imposed) are left out of the support (their φ is 0): the fit then
// uses the remaining ≥ 2 planes (the markers are kept ≥ Δz from the walls, markers.h).
// x and y are periodic: indices wrap.
#include <array>
#include <exception>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include "solver/grid/grid.h"

namespace systole::ibm {

// A point (marker or load probe) whose MLS support has fewer than two node planes inside the
// fluid in some direction: a body came within about a cell of the box's wall. point() is in the
// grid's (nondimensional) coordinates; the scene turns it into a diagnosis with its time.
class WallProximityError : public std::runtime_error {
 public:
  explicit WallProximityError(const Eigen::Vector3d& point);
  const Eigen::Vector3d& point() const { return point_; }

 private:
  Eigen::Vector3d point_;
};

// Runs body(i) for i in [0, n) on the OpenMP threads when n >= threaded (else serially), and
// rethrows the first exception a body threw after the loop (an exception must not leave an
// OpenMP region: the process would abort). Bodies write disjoint data.
template <class Body>
void parallel_for_rethrow(std::ptrdiff_t n, std::ptrdiff_t threaded, Body&& body) {
  std::exception_ptr first;
#pragma omp parallel for schedule(static) if (n >= threaded)
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    try {
      body(i);
    } catch (...) {
#pragma omp critical(systole_ibm_rethrow)
      if (!first) first = std::current_exception();
    }
  }
  if (first) std::rethrow_exception(first);
}

struct MlsStencil {
  // Global indices of the support's first node (i0, j0 wrapped into [0, n); k0 unwrapped: the
  // support is k0..k0+2 and k outside the fluid has φ = 0).
  int i0 = 0, j0 = 0, k0 = 0;
  int k_centre = 0;                 // global index of the centre plane (decides the owner rank)
  // Planes c ∈ [c_begin, c_end) of the support lie in the fluid; the others have φ = 0 (walls).
  int c_begin = 0, c_end = 3;
  std::array<double, 27> phi{};     // shape functions, index a + 3b + 9c for (i0+a, j0+b, k0+c)
};

struct MlsGradientStencil : MlsStencil {
  std::array<std::array<double, 27>, 3> dphi{};  // ∂φ_k/∂x_d at X (full analytic derivative)
};

// Shape functions at X (grid units) for location L. X may lie outside [0, L) in x, y
// (periodic). Throws std::logic_error if the moment matrix is singular (X too close to a wall:
// markers.h prevents it).
MlsStencil mls_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X);

// The three face stencils (u, v, w locations) of one point in one call: the 1-D weights are
// shared (each direction has only two node offsets, face and centre). Same values as three
// mls_stencil calls.
void mls_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<MlsStencil, 3>& out);
// The same three stencils with a divergence-free kernel instead of MLS (ours, after the composite
// B-splines of Gruninger & Griffith 2025, J. Comput. Phys. 546:114472; the volume error it
// addresses: Bao, Donev, Griffith, McQueen & Peskin 2017, J. Comput. Phys. 347:183): component c's
// weight is the quadratic B-spline B₂ in its own direction (faces) and the hat B₁ in the other two
// (centres), φ = B₂(δ_c) Π_{d≠c} B₁(δ_d), δ in cells. Since B₂'(x) = B₁(x + ½) − B₁(x − ½), the
// interpolant U(X) = Σ φ_k u_k has ∇·U(X) = Σ_cells (D·u)_cell B₁B₁B₁(X − x_cell): zero wherever the
// grid field is discretely divergence-free, so the flux of U through any closed surface vanishes
// and a wall the forcing holds at U = V cannot lose the volume it encloses. Σφ = 1 and linear
// fields are reproduced; the support is inside MLS's 3×3×3 block (same first node and centre
// plane). Nodes outside the fluid (the z walls) get φ = 0, as with MLS: with markers kept ≥ Δz
// from the walls only a wall face itself (where w = 0) can carry weight.
void divergence_free_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<MlsStencil, 3>& out);
// The kernel's weights are a tensor product: the same stencils kept as their three 1-D factors,
// φ_abc = x[a] y[b] z[c] (9 numbers instead of 27: what the transfer streams per marker and
// component, ours for cost). The MlsStencil overload forms φ from these (x y then z).
struct TensorStencil {
  int i0 = 0, j0 = 0, k0 = 0;  // as MlsStencil
  int k_centre = 0;
  int c_begin = 0, c_end = 3;
  std::array<double, 3> x{}, y{}, z{};
};
void divergence_free_face_stencils(const grid::Grid& g, const Eigen::Vector3d& X, std::array<TensorStencil, 3>& out);

// One point's 1-D weights in closed form for every staggered location (ours, round 3, for
// cost): per direction d and node offset (0: faces normal to d, 1: centres), the support's
// first node, ŵ_d(a), g_d(a) and (when asked) their derivatives ∂/∂X_d. mls_contract applies
// φ (and ∂φ) of any location to a field row by row without forming the 27-node arrays.
struct MlsAxis {
  int first = 0;  // global index of node a = 0 (unwrapped)
  double w[3]{}, g[3]{}, dw[3]{}, dg[3]{};
};
struct MlsPoint {
  MlsAxis axis[3][2];  // [direction][0: face nodes, 1: centre nodes]
};
// Throws std::logic_error like mls_stencil when a direction's moment is singular.
MlsPoint mls_point(const grid::Grid& g, const Eigen::Vector3d& X, bool derivatives);
// Throws what mls_point throws at X, and nothing else: only the z supports can be singular (x and
// y are periodic), so this is two 1-D supports instead of six with derivatives. For ranks that do
// not own X's planes but must fail alike (collective callers).
void mls_check_point(const grid::Grid& g, const Eigen::Vector3d& X);
// The centre planes (global k) of the z-face and of the other locations' supports at X: what
// mls_k_centre gives for mls_point(g, X, ·), without building it.
inline int mls_k_centre_z_face(const grid::Grid& g, const Eigen::Vector3d& X);
inline int mls_k_centre_cell(const grid::Grid& g, const Eigen::Vector3d& X);

// The centre plane (global k) of location L's support at the point (decides the owner rank).
template <grid::Location L>
int mls_k_centre(const MlsPoint& P) {
  return P.axis[2][L == grid::Location::z_face ? 0 : 1].first + 1;
}

// Σ_k φ_k f_k at the point (eq 5) and, with kGradient, Σ_k ∂φ_k/∂X_d f_k into gradient[d]
// (eq 13): the same φ, ∂φ as mls_stencil / mls_gradient_stencil, summed in another order
// (round-off differs). With A = Σ_a ŵ_x f, B = Σ_a ŵ_x g_x f per row (b, c), W_yz = ŵ_y ŵ_z,
// H_yz = 1 − g_y − g_z:  value = Σ W_yz (H_yz A − B), and the derivatives likewise (mls.cc).
// The support's planes must be local or halo planes of f; planes outside the fluid are skipped.
template <grid::Location L, bool kGradient>
double mls_contract(const grid::Field<L>& f, const MlsPoint& P, double* gradient) {
  using grid::Location;
  const MlsAxis& x = P.axis[0][L == Location::x_face ? 0 : 1];
  const MlsAxis& y = P.axis[1][L == Location::y_face ? 0 : 1];
  const MlsAxis& z = P.axis[2][L == Location::z_face ? 0 : 1];
  const int nx = f.nx(), ny = f.ny();
  const int i0 = ((x.first % nx) + nx) % nx, j0 = ((y.first % ny) + ny) % ny;
  std::ptrdiff_t ii[3], jj[3];
  double xw[3], xwg[3], xdw[3], xd[3];
  for (int a = 0; a < 3; ++a) {
    const int i = i0 + a, j = j0 + a;
    ii[a] = i >= nx ? i - nx : i;
    jj[a] = (j >= ny ? j - ny : j) * f.stride_j();
    xw[a] = x.w[a];
    xwg[a] = x.w[a] * x.g[a];
    xdw[a] = x.dw[a];
    xd[a] = x.dw[a] * x.g[a] + x.w[a] * x.dg[a];
  }
  const double* base = f.data() + f.index(0, 0, z.first - f.k_begin());
  double value = 0, gx = 0, gy = 0, gz = 0;
  for (int c = 0; c < 3; ++c) {
    if (z.w[c] == 0) continue;  // outside the fluid
    const double* plane = base + c * f.stride_k();
    for (int b = 0; b < 3; ++b) {
      const double* row = plane + jj[b];
      const double u0 = row[ii[0]], u1 = row[ii[1]], u2 = row[ii[2]];
      const double A = xw[0] * u0 + xw[1] * u1 + xw[2] * u2;
      const double B = xwg[0] * u0 + xwg[1] * u1 + xwg[2] * u2;
      const double wyz = y.w[b] * z.w[c], hyz = 1.0 - y.g[b] - z.g[c];
      value += wyz * (hyz * A - B);
      if constexpr (kGradient) {
        const double C = xdw[0] * u0 + xdw[1] * u1 + xdw[2] * u2;
        const double D = xd[0] * u0 + xd[1] * u1 + xd[2] * u2;
        const double dwy_z = y.dw[b] * z.w[c], wy_dz = y.w[b] * z.dw[c];
        gx += wyz * (hyz * C - D);
        gy += (dwy_z * hyz - wyz * y.dg[b]) * A - dwy_z * B;
        gz += (wy_dz * hyz - wyz * z.dg[c]) * A - wy_dz * B;
      }
    }
  }
  if constexpr (kGradient) {
    gradient[0] = gx;
    gradient[1] = gy;
    gradient[2] = gz;
  }
  return value;
}

// Shape functions and their analytic derivatives ∂φ_k/∂X (eq 13): differentiating
// φ_k(X) = p(X)ᵀ A(X)⁻¹ W_k(X) p_k, including ∂A⁻¹ = −A⁻¹ ∂A A⁻¹. Σ∂φ_k = 0 and
// Σ ∂φ_k x_k = I: the gradient of a linear field is exact.
MlsGradientStencil mls_gradient_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X);

// The node nearest to v (v in cells, offset removed): round half away from zero, as std::lround
// (inline, no libm call). The stencils' centre planes (ownership) use it.
inline int mls_nearest(double v) { return v >= 0 ? static_cast<int>(v + 0.5) : -static_cast<int>(0.5 - v); }
inline int mls_k_centre_z_face(const grid::Grid& g, const Eigen::Vector3d& X) { return mls_nearest(X[2] / g.dz()); }
inline int mls_k_centre_cell(const grid::Grid& g, const Eigen::Vector3d& X) { return mls_nearest(X[2] / g.dz() - 0.5); }

// The weight function w(r) (r ≥ 0) and its derivative.
double mls_weight(double r);
double mls_weight_derivative(double r);
// Support radius in cells of the weight (2: w(|Δ|/(2h))).
inline constexpr double kMlsRadiusCells = 2.0;

}  // namespace systole::ibm
