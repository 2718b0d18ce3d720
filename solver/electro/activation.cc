#include "solver/electro/activation.h"

#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace systole::electro {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

ActivationTracker::ActivationTracker(std::vector<double> resting_mv, double threshold_mv)
    : rest_mv_(std::move(resting_mv)), threshold_mv_(threshold_mv) {
  reset();
}

void ActivationTracker::reset() {
  activation_ms_.assign(rest_mv_.size(), kNaN);
  repol_ms_.assign(rest_mv_.size(), kNaN);
  peak_mv_.assign(rest_mv_.size(), -std::numeric_limits<double>::infinity());
}

void ActivationTracker::update(double t0, const std::vector<double>& v0, double t1, const std::vector<double>& v1) {
  for (std::size_t i = 0; i < rest_mv_.size(); ++i) {
    if (std::isnan(activation_ms_[i])) {
      if (v0[i] < threshold_mv_ && v1[i] >= threshold_mv_)
        activation_ms_[i] = t0 + (t1 - t0) * (threshold_mv_ - v0[i]) / (v1[i] - v0[i]);
      else
        continue;
    }
    if (!std::isnan(repol_ms_[i])) continue;
    peak_mv_[i] = std::max(peak_mv_[i], v1[i]);
    const double level = rest_mv_[i] + 0.1 * (peak_mv_[i] - rest_mv_[i]);
    if (v0[i] > level && v1[i] <= level) repol_ms_[i] = t0 + (t1 - t0) * (v0[i] - level) / (v0[i] - v1[i]);
  }
}

void ActivationTracker::restore(std::vector<double> activation_ms, std::vector<double> repolarisation_ms,
                                std::vector<double> peak_mv) {
  const std::size_t n = rest_mv_.size();
  if (activation_ms.size() != n || repolarisation_ms.size() != n || peak_mv.size() != n)
    throw std::invalid_argument("ActivationTracker::restore: arrays of " + std::to_string(activation_ms.size()) + ", " +
                                std::to_string(repolarisation_ms.size()) + ", " + std::to_string(peak_mv.size()) +
                                " values for " + std::to_string(n) + " nodes");
  activation_ms_ = std::move(activation_ms);
  repol_ms_ = std::move(repolarisation_ms);
  peak_mv_ = std::move(peak_mv);
}

std::vector<double> ActivationTracker::apd_ms() const {
  std::vector<double> out(rest_mv_.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = repol_ms_[i] - activation_ms_[i];
  return out;
}

}  // namespace systole::electro
