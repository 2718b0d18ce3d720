#include "solver/lumped/activation.h"

#include <cmath>
#include <numbers>

namespace systole::lumped {
namespace {
constexpr double kReferencePeriod_s = 60.0 / 70.0;  // 857.14 ms, the seed's 70 bpm

ChamberTiming make(const config::Scenario& s, const config::Chamber& c, double onset_s) {
  const double period_s = s.period_ms() * 1e-3;
  const double scale = activation_duration_scale(period_s);
  return ChamberTiming{period_s, onset_s, c.contraction_ms * 1e-3 * scale,
                       c.relaxation_ms * 1e-3 * scale};
}
}  // namespace

double activation_duration_scale(double period_s) {
  return std::sqrt(period_s / kReferencePeriod_s);
}

ChamberTiming ChamberTiming::lv(const config::Scenario& s) { return make(s, s.lumped.lv, 0.0); }

ChamberTiming ChamberTiming::la(const config::Scenario& s) {
  const double period_s = s.period_ms() * 1e-3;
  return make(s, s.lumped.la, period_s - s.av_delay_ms * 1e-3);
}

double ChamberTiming::activation(double t_s) const {
  double tau = std::fmod(t_s - onset_s, period_s);
  if (tau < 0) tau += period_s;
  if (tau < contraction_s) return 0.5 * (1.0 - std::cos(std::numbers::pi * tau / contraction_s));
  tau -= contraction_s;
  if (tau < relaxation_s) return 0.5 * (1.0 + std::cos(std::numbers::pi * tau / relaxation_s));
  return 0.0;
}

std::vector<double> ChamberTiming::breakpoints_s() const {
  std::vector<double> out;
  for (double t : {onset_s, onset_s + contraction_s, onset_s + contraction_s + relaxation_s}) {
    double w = std::fmod(t, period_s);
    if (w < 0) w += period_s;
    out.push_back(w);
  }
  return out;
}

}  // namespace systole::lumped
