#include "uq/ishigami.h"

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace systole::uq {

double ishigami(std::span<const double> x, double a, double b) {
  if (x.size() != 3)
    throw std::invalid_argument("ishigami: input size = " + std::to_string(x.size()) +
                                " is out of range (must be 3)");
  const double s1 = std::sin(x[0]);
  const double s2 = std::sin(x[1]);
  const double x3 = x[2];
  return s1 + a * s2 * s2 + b * x3 * x3 * x3 * x3 * s1;
}

IshigamiExact ishigami_exact(double a, double b) {
  const double pi4 = std::pow(std::numbers::pi, 4), pi8 = pi4 * pi4;
  const double v1 = 0.5 * (1.0 + b * pi4 / 5.0) * (1.0 + b * pi4 / 5.0);
  const double v2 = a * a / 8.0;
  const double v13 = 8.0 * b * b * pi8 / 225.0;
  IshigamiExact e;
  e.mean = a / 2.0;
  e.variance = a * a / 8.0 + b * pi4 / 5.0 + b * b * pi8 / 18.0 + 0.5;  // = v1 + v2 + v13
  e.first_order = {v1 / e.variance, v2 / e.variance, 0.0};
  e.total = {(v1 + v13) / e.variance, v2 / e.variance, v13 / e.variance};
  return e;
}

}  // namespace systole::uq
