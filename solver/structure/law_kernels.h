#pragma once
// Inline stress laws shared by the registry (spring_law.cc) and the force loop (shell.cc),
// so the hot loop is specialised per law. See spring_law.h for the formulas and units.
#include <cmath>

namespace systole::structure {
// Parameters of the laws beyond c and alpha (read by fung_tension only).
struct LawParams {
  double q_cap = 4;                 // largest Fung exponent a eps^2 before the linear continuation
  double compression_fraction = 0;  // share of the Fung stiffening kept in compression
};
}  // namespace systole::structure

namespace systole::structure::kernels {

// Each law: stress(eps) and tangent(eps), and both at once (one exp for the force loop). LawParams
// are read by FungTension only.
struct Fung {
  static void stress_tangent(double eps, double c, double a, const LawParams& /*lp*/, double& tau, double& dtau) {
    const double q = a * eps * eps;
    const double ca_e = c * a * std::exp(q);
    tau = ca_e * eps;
    dtau = ca_e * (1 + 2 * q);
  }
  static double stress(double eps, double c, double a) { return c * a * std::exp(a * eps * eps) * eps; }
  static double tangent(double eps, double c, double a) {
    const double q = a * eps * eps;
    return c * a * std::exp(q) * (1 + 2 * q);
  }
};
struct Linear {
  static void stress_tangent(double eps, double c, double a, const LawParams& /*lp*/, double& tau, double& dtau) {
    tau = c * a * eps;
    dtau = c * a;
  }
  static double stress(double eps, double c, double a) { return c * a * eps; }
  static double tangent(double, double c, double a) { return c * a; }
};
// Fung in tension only (ours, spring_law.h "fung_tension"): eq 17 for eps >= 0 until the exponent
// q = a eps^2 reaches q_cap, then continued linearly with the tangent there (C1), so the tangent
// is bounded by c a e^{q_cap} (1 + 2 q_cap); in compression the small-strain modulus c a eps plus
// a fraction r (compression_fraction) of the capped law's stiffening: r = 0, a fibre that
// shortens does not stiffen; r = 1, the capped Fung law in both directions.
struct FungTension {
  // The Fung law with its exponent capped (odd in eps).
  static void capped(double eps, double c, double a, double q_cap, double& tau, double& dtau) {
    const double q = a * eps * eps;
    if (q <= q_cap) {
      const double ca_e = c * a * std::exp(q);
      tau = ca_e * eps;
      dtau = ca_e * (1 + 2 * q);
      return;
    }
    const double eps_cap = std::copysign(std::sqrt(q_cap / a), eps);
    const double ca_e = c * a * std::exp(q_cap);
    dtau = ca_e * (1 + 2 * q_cap);
    tau = ca_e * eps_cap + dtau * (eps - eps_cap);
  }
  static void stress_tangent(double eps, double c, double a, const LawParams& lp, double& tau, double& dtau) {
    if (eps >= 0) {
      capped(eps, c, a, lp.q_cap, tau, dtau);
      return;
    }
    // compression: linear, plus the fraction r of the capped Fung law's stiffening
    const double r = lp.compression_fraction;
    tau = c * a * eps;
    dtau = c * a;
    if (r > 0) {
      double tf, df;
      capped(eps, c, a, lp.q_cap, tf, df);
      tau += r * (tf - c * a * eps);
      dtau += r * (df - c * a);
    }
  }
};
// lambda = l / l0 = 1 / (1 - eps); tau = (c a / 3)(lambda - lambda^-2).
struct NeoHookean {
  static void stress_tangent(double eps, double c, double a, const LawParams& /*lp*/, double& tau, double& dtau) {
    tau = stress(eps, c, a);
    dtau = tangent(eps, c, a);
  }
  static double stress(double eps, double c, double a) {
    const double lam = 1 / (1 - eps);
    return c * a / 3 * (lam - 1 / (lam * lam));
  }
  static double tangent(double eps, double c, double a) {
    const double lam = 1 / (1 - eps);
    return c * a / 3 * (1 + 2 / (lam * lam * lam)) * lam * lam;  // d lambda / d eps = lambda^2
  }
};

}  // namespace systole::structure::kernels
