#include "solver/structure/spring_law.h"

#include <cmath>

#include "solver/core/errors.h"
#include "solver/structure/law_kernels.h"

namespace systole::structure {
namespace {

double fung_stress(double e, double c, double a, const LawParams&) { return kernels::Fung::stress(e, c, a); }
double fung_tangent(double e, double c, double a, const LawParams&) { return kernels::Fung::tangent(e, c, a); }
double linear_stress(double e, double c, double a, const LawParams&) { return kernels::Linear::stress(e, c, a); }
double linear_tangent(double e, double c, double a, const LawParams&) { return kernels::Linear::tangent(e, c, a); }
double neo_stress(double e, double c, double a, const LawParams&) { return kernels::NeoHookean::stress(e, c, a); }
double neo_tangent(double e, double c, double a, const LawParams&) { return kernels::NeoHookean::tangent(e, c, a); }
double fung_tension_stress(double e, double c, double a, const LawParams& lp) {
  double tau, dtau;
  kernels::FungTension::stress_tangent(e, c, a, lp, tau, dtau);
  return tau;
}
double fung_tension_tangent(double e, double c, double a, const LawParams& lp) {
  double tau, dtau;
  kernels::FungTension::stress_tangent(e, c, a, lp, tau, dtau);
  return dtau;
}

// 20-point Gauss-Legendre nodes and weights on [-1, 1] (positive half; symmetric).
constexpr double kGlX[10] = {0.0765265211334973, 0.2277858511416451, 0.3737060887154195,
                             0.5108670019508271, 0.6360536807265150, 0.7463319064601508,
                             0.8391169718222188, 0.9122344282513259, 0.9639719272779138,
                             0.9931285991850949};
constexpr double kGlW[10] = {0.1527533871307258, 0.1491729864726037, 0.1420961093183820,
                             0.1316886384491766, 0.1181945319615184, 0.1019301198172404,
                             0.0832767415767048, 0.0626720483341091, 0.0406014298003869,
                             0.0176140071391521};

}  // namespace

const std::vector<SpringLaw>& spring_laws() {
  static const std::vector<SpringLaw> laws{
      {"fung", "Fung exponential (eq 17): tau = c a e^{a eps^2} eps", LawKind::kFung, fung_stress,
       fung_tangent},
      {"linear", "Hookean: tau = c a eps (the Fung law's small-strain modulus)", LawKind::kLinear,
       linear_stress, linear_tangent},
      {"neo_hookean",
       "uniaxial incompressible neo-Hookean: tau = (c a / 3)(lambda - lambda^-2), lambda = l/l0",
       LawKind::kNeoHookean, neo_stress, neo_tangent},
      {"fung_tension",
       "Fung in tension with the exponent capped at q_cap (then linear); in compression c a eps plus a fraction of the capped stiffening (ours)",
       LawKind::kFungTension, fung_tension_stress, fung_tension_tangent},
  };
  return laws;
}

std::string known_spring_laws() {
  std::string s;
  for (const auto& law : spring_laws()) s += (s.empty() ? "" : ", ") + std::string(law.name);
  return s;
}

const SpringLaw& find_spring_law(std::string_view name) {
  for (const auto& law : spring_laws())
    if (law.name == name) return law;
  throw InputError("unknown spring law '" + std::string(name) + "'; known: " + known_spring_laws());
}

double alpha_phi(double alpha_f, double alpha_c, double cos2_phi) {
  return std::sqrt(alpha_f * alpha_f * cos2_phi + alpha_c * alpha_c * (1 - cos2_phi));
}

double edge_energy(const SpringLaw& law, double eps, double c_kpa, double alpha, const LawParams& lp,
                   double cross_section_mm3) {
  const double half = 0.5 * eps;
  double sum = 0;
  for (int k = 0; k < 10; ++k) {
    for (double sign : {-1.0, 1.0}) {
      const double e = half + sign * half * kGlX[k];
      sum += kGlW[k] * law.stress(e, c_kpa, alpha, lp) / (1 - e);
    }
  }
  return cross_section_mm3 * half * sum;
}

}  // namespace systole::structure
