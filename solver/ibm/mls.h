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
// Weight (ours; the paper names no kernel): W_k = Π_d w(|x_k,d − X_d| / (2Δ_d)) with the cubic
// B-spline w(r) = 2/3 − 4r² + 4r³ (r ≤ ½), 4/3 (1 − r)³ (½ < r ≤ 1): positive on all 27 nodes
// (r ≤ ¾), smooth, compact.
// Walls: nodes outside the fluid in z (cell levels k ∉ [0, nz); z-faces k ∉ [1, nz−1], the
// wall faces where w = 0 is imposed) are left out of the support (their φ is 0): the fit then
// uses the remaining ≥ 2 planes (the markers are kept ≥ Δz from the walls, markers.h).
// x and y are periodic: indices wrap.
#include <array>

#include <Eigen/Core>

#include "solver/grid/grid.h"

namespace systole::ibm {

struct MlsStencil {
  // Global indices of the support's first node (i0, j0 wrapped into [0, n); k0 unwrapped: the
  // support is k0..k0+2 and k outside the fluid has φ = 0).
  int i0 = 0, j0 = 0, k0 = 0;
  int k_centre = 0;                 // global index of the centre plane (decides the owner rank)
  std::array<double, 27> phi{};     // shape functions, index a + 3b + 9c for (i0+a, j0+b, k0+c)
};

struct MlsGradientStencil : MlsStencil {
  std::array<std::array<double, 27>, 3> dphi{};  // ∂φ_k/∂x_d at X (full analytic derivative)
};

// Shape functions at X (grid units) for location L. X may lie outside [0, L) in x, y
// (periodic). Throws std::logic_error if the moment matrix is singular (X too close to a wall:
// markers.h prevents it).
MlsStencil mls_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X);

// Shape functions and their analytic derivatives ∂φ_k/∂X (eq 13): differentiating
// φ_k(X) = p(X)ᵀ A(X)⁻¹ W_k(X) p_k, including ∂A⁻¹ = −A⁻¹ ∂A A⁻¹. Σ∂φ_k = 0 and
// Σ ∂φ_k x_k = I: the gradient of a linear field is exact.
MlsGradientStencil mls_gradient_stencil(const grid::Grid& g, grid::Location L, const Eigen::Vector3d& X);

// The weight function w(r) (r ≥ 0) and its derivative.
double mls_weight(double r);
double mls_weight_derivative(double r);
// Support radius in cells of the weight (2: w(|Δ|/(2h))).
inline constexpr double kMlsRadiusCells = 2.0;

}  // namespace systole::ibm
