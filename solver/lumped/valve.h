#pragma once
// Smooth diode valve law (ours): flow = g(dp) * dp with
//   g(dp) = g_closed                                   for dp <= 0,
//   g(dp) = g_closed + (g_open - g_closed) s(dp / w)   for 0 < dp < w,
//   g(dp) = g_open                                     for dp >= w,
// s(x) = 6x^5 - 15x^4 + 10x^3 (quintic smoothstep), w = kTransitionWidth_mmhg.
// The flow is monotone increasing in dp and twice continuously differentiable, exactly linear
// (the leak) when closed and exactly linear (1 / R_open) when open beyond w.
namespace systole::lumped {

class SmoothDiode {
 public:
  // Width of the opening transition in pressure drop (ours): small against the open-valve
  // drops of a healthy heart (mitral E wave ~2 mmHg, aortic ejection ~5 mmHg across R + Zc).
  static constexpr double kTransitionWidth_mmhg = 0.1;

  // open_resistance > 0; closed_resistance > 0 or +infinity (no leak).
  SmoothDiode(double open_resistance_mmhg_s_per_ml, double closed_resistance_mmhg_s_per_ml);

  double flow_ml_s(double dp_mmhg) const {
    if (dp_mmhg <= 0) return g_closed_ * dp_mmhg;
    if (dp_mmhg >= kTransitionWidth_mmhg) return g_open_ * dp_mmhg;
    const double x = dp_mmhg * kInvWidth;
    const double s = x * x * x * (10.0 + x * (-15.0 + 6.0 * x));
    return (g_closed_ + (g_open_ - g_closed_) * s) * dp_mmhg;
  }
  // d(flow)/d(dp) >= g_closed.
  double conductance_slope(double dp_mmhg) const;

  double open_conductance() const { return g_open_; }
  double closed_conductance() const { return g_closed_; }

 private:
  static constexpr double kInvWidth = 1.0 / kTransitionWidth_mmhg;
  double g_open_;
  double g_closed_;
};

}  // namespace systole::lumped
