#include "solver/lumped/valve.h"

#include <cmath>
#include <stdexcept>

namespace systole::lumped {

SmoothDiode::SmoothDiode(double open_resistance, double closed_resistance)
    : g_open_(1.0 / open_resistance),
      g_closed_(std::isinf(closed_resistance) ? 0.0 : 1.0 / closed_resistance) {
  if (!(open_resistance > 0) || !(closed_resistance >= open_resistance))
    throw std::invalid_argument("SmoothDiode: need 0 < open resistance <= closed resistance");
}

double SmoothDiode::conductance_slope(double dp) const {
  if (dp <= 0) return g_closed_;
  if (dp >= kTransitionWidth_mmhg) return g_open_;
  const double x = dp * kInvWidth;
  const double s = x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
  const double ds_dx = 30.0 * x * x * (1.0 - x) * (1.0 - x);
  // d/d(dp) [g(dp) dp] = g + dp g' = g + (g_open - g_closed) x s'(x)
  return g_closed_ + (g_open_ - g_closed_) * (s + x * ds_dx);
}

}  // namespace systole::lumped
