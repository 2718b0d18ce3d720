#pragma once
#include <array>

// Shear-thinning (generalised Newtonian) viscosity: the Carreau–Yasuda law (MODEL.md §3,
// "optional Carreau–Yasuda shear-thinning viscosity"), nondimensional in the fluid's units
// (lengths d_m, velocities U_m: ν* = μ / (ρ U_m d_m), λ* = λ U_m / d_m), plus the steady
// plane-Poiseuille profile of such a fluid, computed independently of the 3-D solver, used
// as the reference of its verification.
namespace systole::fluid {

// ν(γ̇) = ν∞ + (ν0 − ν∞) [1 + (λ γ̇)^a]^((n − 1)/a), γ̇ = √(2 S:S), S = ½(∇u + ∇uᵀ).
// Shear-thinning only (checked by validate): 0 < n ≤ 1 and 0 ≤ ν∞ ≤ ν0, so ν ∈ [ν∞, ν0] and
// the shear stress ν(γ̇)γ̇ increases strictly with γ̇. n = 1 or ν0 = ν∞ is Newtonian (ν ≡ ν0).
struct CarreauYasuda {
  double nu0 = 0;     // zero-shear viscosity, nondimensional (1/Re of the zero-shear limit)
  double nu_inf = 0;  // infinite-shear viscosity, nondimensional
  double lambda = 0;  // time constant, nondimensional (units of d_m/U_m)
  double n = 1;       // power-law index, (0, 1]
  double a = 2;       // Yasuda transition exponent, > 0 (a = 2: the Carreau law)

  double operator()(double shear_rate) const;
  // The same from γ̇² (what the solver has): no square root, and one pow instead of two when
  // a = 2 (the Carreau case).
  double from_shear_rate_squared(double shear_rate_squared) const;
};

// The same law in SI units. Defaults: whole blood, Cho & Kensey, Biorheology 28 (1991) 241–262
// (their Carreau fit, i.e. a = 2): μ0 = 0.056 Pa·s, μ∞ = 0.00345 Pa·s, λ = 3.313 s,
// n = 0.3568; blood density ρ = 1060 kg/m³ (ours: the usual whole-blood value; the tissue
// density of the seed, 1.05 g/ml, is not the blood's).
struct CarreauYasudaSI {
  double mu0_pa_s = 0.056;
  double mu_inf_pa_s = 0.00345;
  double lambda_s = 3.313;
  double n = 0.3568;
  double a = 2;
  double density_kg_per_m3 = 1060;
};

// ν* = μ/(ρ U d), λ* = λ U/d with the length and velocity scales d, U (the seed's d_m = 0.024 m,
// U_m = 0.6 m/s: blood gives ν0* = 3.669e-3 (Re0 = 272.6), ν∞* = 2.260e-4 (Re∞ = 4424),
// λ* = 82.83).
CarreauYasuda nondimensional(const CarreauYasudaSI& si, double length_m, double velocity_m_s);

// The nondimensional blood law at the seed scales (the FluidParameters default).
CarreauYasuda blood_carreau_yasuda();

// Throws InputError naming fluid.carreau_yasuda.<field>, its value and the allowed range.
void validate(const CarreauYasuda& law);

// Simple shear s = du/dz: stress τ(s) = ν(|s|) s, and its inverse s(τ) (bisection to round-off).
double shear_stress(const CarreauYasuda& law, double shear_rate);
double shear_rate_for_stress(const CarreauYasuda& law, double stress);

// Steady plane Poiseuille flow between no-slip walls at z = 0 and z = h, driven by a uniform
// body force G (a pressure gradient −G) along x. The momentum balance integrates to
// τ(z) = G (h/2 − z), so u(z) = ∫₀^z s(τ(ζ)) dζ, evaluated by composite 8-point Gauss–Legendre
// quadrature of s(τ) over 64 panels (error ≈ 1e-14 of the peak for the blood law). This solves
// the 1-D problem exactly up to quadrature: no grid, no time stepping, no 3-D operator.
double plane_poiseuille_velocity(const CarreauYasuda& law, double body_force, double height, double z);

// Vreman's subgrid eddy viscosity (ours: not in the seed, whose grid-1 run is a DNS; A. W. Vreman,
// "An eddy-viscosity subgrid-scale model for turbulent shear flow: algebraic theory and
// applications", Phys. Fluids 16 (2004) 3670–3681):
//   ν_e = c √(B_β / (α_ij α_ij)),  α_ij = ∂u_j/∂x_i,  β_ij = Σ_m Δ_m² α_mi α_mj,
//   B_β = β11β22 − β12² + β11β33 − β13² + β22β33 − β23²  (≥ 0),
// and ν_e = 0 where α = 0. c ≈ 2.5 C_s² with C_s the Smagorinsky constant (Vreman's paper).
// ν_e vanishes wherever the gradient has rank ≤ 1, e.g. in any unidirectional shear flow
// (Couette, Poiseuille, a laminar shear layer or boundary layer), and is O(Δ²) on smooth flows.
// grad[3 i + j] = α_ij = ∂u_j/∂x_i; dx, dy, dz the grid spacings Δ_1..3; c > 0.
double vreman_eddy_viscosity(const std::array<double, 9>& grad, double dx, double dy, double dz, double c);

}  // namespace systole::fluid
