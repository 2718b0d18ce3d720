#pragma once
// The Ishigami function (Ishigami & Homma 1990), the standard test case of variance-based
// sensitivity analysis, with its exact Sobol' indices:
//   f(x) = sin x1 + a sin^2 x2 + b x3^4 sin x1,   x1, x2, x3 ~ U(-pi, pi) independent.
// Exact moments and partial variances (Sobol' & Levitan 1999; also Saltelli et al. 2000,
// "Sensitivity Analysis", and Marrel et al. 2009, Reliab. Eng. Syst. Saf. 94, 742):
//   E f  = a / 2
//   V    = a^2/8 + b pi^4/5 + b^2 pi^8/18 + 1/2
//   V1   = (1 + b pi^4/5)^2 / 2,   V2 = a^2/8,   V3 = 0,
//   V13  = b^2 pi^8 (1/18 - 1/50) = 8 b^2 pi^8 / 225,   V12 = V23 = V123 = 0
//   S_i  = V_i / V;   ST1 = (V1 + V13)/V,  ST2 = V2/V,  ST3 = V13/V.
// For a = 7, b = 0.1: S = (0.3139, 0.4424, 0), ST = (0.5576, 0.4424, 0.2437).
#include <array>
#include <span>

namespace systole::uq {

inline constexpr double kIshigamiA = 7.0;
inline constexpr double kIshigamiB = 0.1;

// x = (x1, x2, x3) in radians (any real values; the test case draws them from U(-pi, pi)).
// std::invalid_argument if x.size() != 3.
double ishigami(std::span<const double> x, double a = kIshigamiA, double b = kIshigamiB);

struct IshigamiExact {
  double mean = 0;
  double variance = 0;
  std::array<double, 3> first_order{};
  std::array<double, 3> total{};
};
IshigamiExact ishigami_exact(double a = kIshigamiA, double b = kIshigamiB);

}  // namespace systole::uq
