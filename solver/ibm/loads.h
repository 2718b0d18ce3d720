#pragma once
// Hydrodynamic loads on the immersed surfaces (MODEL.md §4, eq 11–14) and wall shear stress
// (eq 27), nondimensional (stress in ρU², force in ρU²d²).
//
// For each active marker b with unit normal n (into the blood for one-sided bodies; the "+"
// side for two-sided ones) a probe sits at x_p = X_b + h n (and x_p⁻ = X_b − h n for two-sided
// bodies). At the probe the pressure p and the velocity gradient G = ∇u come from MLS (the
// analytic derivatives of the shape functions, mls.h; eq 13), τ = Re⁻¹(G + Gᵀ). The wall
// pressure is extrapolated with the wall-normal momentum balance, eq 14:
//     p(X_b) = p(x_p) + h (DV_b/Dt)·n          (the − side: p(x_p⁻) − h (DV_b/Dt)·n)
// (ours: the viscous part of ∂p/∂n is neglected, as in the paper). The load on the tissue:
//     one-sided (eq 11):  F_b = (−p n + τ·n) A_b
//     two-sided (eq 12):  F_b = [−(p⁺ − p⁻) n + (τ⁺ − τ⁻)·n] A_b
// τ is taken at the probe (ours, following eq 13: no extrapolation of τ to the wall).
// WSS (eq 27): |t − (t·n) n|, t = τ·n, on each wetted side.
// Nodal forces: F_b split equally over the tile's three nodes (ours), per body.
//
// Distribution: the probe's pressure and each velocity component's gradient are computed by
// the rank owning the centre plane of that location's support (transfer.h), then summed over
// ranks: every rank gets the same loads (np = 1 values bitwise).
#include <vector>

#include "solver/ibm/transfer.h"

namespace systole::ibm {

struct MarkerLoads {
  std::vector<Vec3> force;             // on the tissue, per marker (0 for inactive markers)
  std::vector<double> wall_pressure;   // p(X_b), eq 14 ("+" side for two-sided bodies)
  std::vector<double> wall_pressure_minus;  // two-sided bodies: p(X_b) on the − side; else 0
  std::vector<double> wss;             // eq 27, "+" side (the wetted side of one-sided bodies)
  std::vector<double> wss_minus;       // eq 27, − side of two-sided bodies; else 0
  std::vector<std::vector<Vec3>> nodal_force;  // per body, per tiled node
  Vec3 total_force = Vec3::Zero();     // Σ_b F_b over active markers
};

// Pressure and velocity gradient at arbitrary points, from MLS (eq 13). Collective.
struct ProbeValues {
  std::vector<double> pressure;
  std::vector<Eigen::Matrix3d> velocity_gradient;  // G(i,j) = ∂u_i/∂x_j
};
ProbeValues probe(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                  const std::vector<Vec3>& points);

// Loads on every marker of transfer.markers(). reynolds: τ = Re⁻¹(∇u + ∇uᵀ). acceleration: DV_b/Dt
// per marker for eq 14 (empty: zero, fixed bodies). bodies: which bodies (by index) to load
// (empty: all); the others are neither probed nor loaded (their entries 0, as inactive markers'),
// e.g. a rigid body whose loads nothing uses. Halos of u and p must be valid. Collective: every
// rank passes the same `bodies`.
MarkerLoads compute_loads(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                          double reynolds, const std::vector<Vec3>& acceleration = {},
                          const std::vector<bool>& bodies = {});

// Wall shear stress (eq 27) extrapolated to the wall (ours): the viscous traction t = τ·n from
// MLS at two probes, X_b + h n and X_b + 2h n (and the mirrored pair on the − side of two-sided
// bodies), extrapolated linearly to the surface, t_w = 2 t(h) − t(2h); WSS = |t_w − (t_w·n) n|.
// compute_loads' WSS takes τ at the single probe h off the wall (eq 13), first order in h with
// a large constant inside thin boundary layers (docs/ibm.md, Womersley). Twice the probes of
// the loads: for output times, not every step. Inactive markers get 0. Collective.
struct WallShear {
  std::vector<double> plus;   // "+" side (the wetted side of one-sided bodies)
  std::vector<double> minus;  // − side of two-sided bodies; else 0
};
WallShear wall_shear_stress(const Transfer& transfer, const ConstVelocityView& u, const grid::CellField& p,
                            double reynolds);

}  // namespace systole::ibm
