#include "solver/fluid/viscosity.h"

#include <array>
#include <cmath>
#include <numbers>
#include <sstream>
#include <string>

#include "solver/core/errors.h"
#include "solver/core/units.h"

namespace systole::fluid {

double CarreauYasuda::operator()(double shear_rate) const {
  return nu_inf + (nu0 - nu_inf) * std::pow(1.0 + std::pow(lambda * shear_rate, a), (n - 1.0) / a);
}

double CarreauYasuda::from_shear_rate_squared(double g2) const {
  const double x = lambda * lambda * g2;  // (λγ̇)²
  const double xa = a == 2 ? x : std::pow(x, 0.5 * a);
  return nu_inf + (nu0 - nu_inf) * std::pow(1.0 + xa, (n - 1.0) / a);
}

CarreauYasuda nondimensional(const CarreauYasudaSI& si, double length_m, double velocity_m_s) {
  const double viscosity_scale = si.density_kg_per_m3 * velocity_m_s * length_m;  // ρ U d, Pa·s
  CarreauYasuda law;
  law.nu0 = si.mu0_pa_s / viscosity_scale;
  law.nu_inf = si.mu_inf_pa_s / viscosity_scale;
  law.lambda = si.lambda_s * velocity_m_s / length_m;
  law.n = si.n;
  law.a = si.a;
  return law;
}

CarreauYasuda blood_carreau_yasuda() {
  return nondimensional(CarreauYasudaSI{}, units::kSeedLength_m, units::kSeedVelocity_m_s);
}

void validate(const CarreauYasuda& c) {
  auto bad = [](const std::string& field, double value, const std::string& allowed) {
    std::ostringstream m;
    m << "fluid.carreau_yasuda." << field << " = " << value << " is out of range " << allowed;
    throw InputError(m.str());
  };
  if (!(c.nu0 > 0 && std::isfinite(c.nu0))) bad("nu0", c.nu0, "(0, inf) nondimensional");
  if (!(c.nu_inf >= 0 && c.nu_inf <= c.nu0))
    bad("nu_inf", c.nu_inf, "[0, nu0] (shear thinning: the infinite-shear viscosity may not exceed the zero-shear one)");
  if (!(c.lambda >= 0 && std::isfinite(c.lambda))) bad("lambda", c.lambda, "[0, inf) nondimensional");
  if (!(c.n > 0 && c.n <= 1)) bad("n", c.n, "(0, 1] (shear thinning; n = 1 is Newtonian)");
  if (!(c.a > 0 && std::isfinite(c.a))) bad("a", c.a, "(0, inf)");
}

double shear_stress(const CarreauYasuda& law, double s) { return law(std::abs(s)) * s; }

double shear_rate_for_stress(const CarreauYasuda& law, double tau) {
  if (tau == 0) return 0;
  const double t = std::abs(tau);
  // ν ∈ [ν∞, ν0] ⇒ s ∈ [t/ν0, t/ν∞]; τ(s) is strictly increasing, so bisection converges.
  double lo = t / law.nu0;
  double hi = law.nu_inf > 0 ? t / law.nu_inf : 2 * lo;
  while (law.nu_inf <= 0 && shear_stress(law, hi) < t) hi *= 2;
  for (int it = 0; it < 200 && hi - lo > 1e-16 * hi; ++it) {
    const double mid = 0.5 * (lo + hi);
    (shear_stress(law, mid) < t ? lo : hi) = mid;
  }
  const double s = 0.5 * (lo + hi);
  return tau > 0 ? s : -s;
}

namespace {
// Nodes and weights of the 8-point Gauss–Legendre rule on [−1, 1] (Newton on P₈).
struct GaussLegendre8 {
  std::array<double, 8> x{}, w{};
  GaussLegendre8() {
    constexpr int n = 8;
    for (int i = 0; i < n; ++i) {
      double z = std::cos(std::numbers::pi * (i + 0.75) / (n + 0.5));
      double dp = 0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1, p1 = z;
        for (int k = 2; k <= n; ++k) {
          const double p2 = ((2 * k - 1) * z * p1 - (k - 1) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = n * (z * p1 - p0) / (z * z - 1);
        const double step = p1 / dp;
        z -= step;
        if (std::abs(step) < 1e-16) break;
      }
      x[i] = z;
      w[i] = 2 / ((1 - z * z) * dp * dp);
    }
  }
};
}  // namespace

double plane_poiseuille_velocity(const CarreauYasuda& law, double G, double h, double z) {
  static const GaussLegendre8 rule;
  if (z > 0.5 * h) z = h - z;  // symmetric about the mid-plane
  if (z <= 0) return 0;
  constexpr int panels = 64;
  const double width = z / panels;
  double sum = 0;
  for (int p = 0; p < panels; ++p) {
    const double mid = (p + 0.5) * width;
    for (int q = 0; q < 8; ++q) {
      const double zeta = mid + 0.5 * width * rule.x[q];
      sum += rule.w[q] * shear_rate_for_stress(law, G * (0.5 * h - zeta));
    }
  }
  return 0.5 * width * sum;
}

double vreman_eddy_viscosity(const std::array<double, 9>& a, double dx, double dy, double dz, double c) {
  double aa = 0;
  for (double x : a) aa += x * x;
  if (aa == 0) return 0;
  const double d2[3] = {dx * dx, dy * dy, dz * dz};
  double b[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = i; j < 3; ++j) {
      double s = 0;
      for (int m = 0; m < 3; ++m) s += d2[m] * a[3 * m + i] * a[3 * m + j];
      b[i][j] = s;
    }
  const double bb = b[0][0] * b[1][1] - b[0][1] * b[0][1] + b[0][0] * b[2][2] - b[0][2] * b[0][2] +
                    b[1][1] * b[2][2] - b[1][2] * b[1][2];
  return bb > 0 ? c * std::sqrt(bb / aa) : 0.0;  // B_β ≥ 0 in exact arithmetic; round-off may not be
}

}  // namespace systole::fluid
