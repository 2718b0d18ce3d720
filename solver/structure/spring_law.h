#pragma once
// In-plane spring laws (MODEL.md §5, eq 16-18) as entries of a registry selectable by name.
//
// Contract: a law maps the seed's edge strain eps = (l - l0) / l (eq 17) to a stress tau in
// kPa, given the tissue's c (kPa) and the edge's exponent alpha_phi (nondimensional). Every law
// has the same small-strain modulus d tau / d eps (0) = c * alpha_phi, so switching the law
// by name changes only the large-strain response:
//   fung        tau = c a e^{a eps^2} eps                        (eq 17, the seed)
//   linear      tau = c a eps
//   neo_hookean tau = (c a / 3) (lambda - lambda^-2), lambda = l / l0 = 1 / (1 - eps)
//               (uniaxial incompressible neo-Hookean nominal stress, mu = c a / 3) (ours)
//   fung_tension tau = fung for eps >= 0 while a eps^2 <= q_cap, continued linearly with the
//               tangent at a eps^2 = q_cap beyond; tau = c a eps (+ a fraction r of the capped
//               law's stiffening) for eps < 0 (ours: the
//               exponential stiffening in tension only, and bounded, so the explicit stable step
//               stays bounded; docs/electromechanics.md "Tissue law")
// The stateless functions are pure and cheap; the force loop is templated on the law.
#include <string>
#include <string_view>
#include <vector>

#include "solver/structure/law_kernels.h"

namespace systole::structure {

enum class LawKind { kFung, kLinear, kNeoHookean, kFungTension };

struct SpringLaw {
  std::string_view name;
  std::string_view doc;
  LawKind kind;
  // tau(eps) in kPa and d tau / d eps in kPa; LawParams are read by fung_tension only.
  double (*stress)(double eps, double c_kpa, double alpha, const LawParams& lp);
  double (*tangent)(double eps, double c_kpa, double alpha, const LawParams& lp);
};

// Every registered law, in a fixed order.
const std::vector<SpringLaw>& spring_laws();
// Throws systole::InputError "unknown spring law 'x'; known: fung, linear, neo_hookean, fung_tension".
const SpringLaw& find_spring_law(std::string_view name);
// "fung, linear, neo_hookean, fung_tension".
std::string known_spring_laws();

// alpha_phi = sqrt(alpha_f^2 cos^2 phi + alpha_c^2 sin^2 phi), cos2 = cos^2 phi
// (MODEL.md §5, (ours): the paper's formula is garbled in the text).
double alpha_phi(double alpha_f, double alpha_c, double cos2_phi);

// Energy of one edge spring, with the (ours) conservative form of eq 18: the force magnitude
// is f = tau(eps) * C / l with C = sum over the edge's triangles of s_T A_T (stress-free
// thickness times area, frozen), so U(eps) = C * int_0^eps tau(e) / (1 - e) de
// (20-point Gauss-Legendre; exact to round-off for |eps| < 0.7 with the seed's alphas).
double edge_energy(const SpringLaw& law, double eps, double c_kpa, double alpha, const LawParams& lp,
                   double cross_section_mm3);

}  // namespace systole::structure
