#include "solver/diagnostics/phase_average.h"

#include <cmath>
#include <stdexcept>

namespace systole::diagnostics {

PhaseAverage phase_average(const std::vector<double>& time_s, const std::vector<double>& values, double period_s,
                           int bins, int discard) {
  if (time_s.size() != values.size())
    throw std::invalid_argument("phase_average: " + std::to_string(values.size()) + " values for " +
                                std::to_string(time_s.size()) + " times");
  if (!(period_s > 0)) throw std::invalid_argument("phase_average: period " + std::to_string(period_s) + " s must be > 0");
  if (bins < 1) throw std::invalid_argument("phase_average: bins = " + std::to_string(bins) + " must be >= 1");
  PhaseAverage out;
  if (time_s.empty()) return out;
  const double tol = 1e-9;
  const int whole = static_cast<int>(std::floor((time_s.back() + tol) / period_s));
  if (time_s.front() > tol || whole - discard < 1) return out;
  out.first_beat = discard + 1;
  out.beats = whole - discard;
  const auto nb = static_cast<std::size_t>(bins);
  out.phase.resize(nb);
  for (std::size_t j = 0; j < nb; ++j) out.phase[j] = (static_cast<double>(j) + 0.5) / bins;
  // per beat and bin: the mean of its samples
  std::vector<double> value(static_cast<std::size_t>(out.beats) * nb, 0.0);
  std::vector<int> count(value.size(), 0);
  for (std::size_t i = 0; i < time_s.size(); ++i) {
    const double beats_in = time_s[i] / period_s;
    int k = static_cast<int>(std::floor(beats_in + tol / period_s));
    double phase = beats_in - k;
    if (phase < 0) phase = 0;  // within the tolerance below a beat's start
    if (k < discard || k >= whole) continue;
    // a sample on a bin's lower edge (to round-off) belongs to that bin
    const auto j = std::min(nb - 1, static_cast<std::size_t>(std::floor(phase * bins + 1e-9)));
    const std::size_t slot = static_cast<std::size_t>(k - discard) * nb + j;
    value[slot] += values[i];
    ++count[slot];
  }
  out.mean.assign(nb, 0.0);
  out.rms.assign(nb, 0.0);
  for (int b = 0; b < out.beats; ++b)
    for (std::size_t j = 0; j < nb; ++j) {
      const std::size_t slot = static_cast<std::size_t>(b) * nb + j;
      if (count[slot] == 0)
        throw std::invalid_argument("phase_average: beat " + std::to_string(b + out.first_beat) + " has no sample in bin " +
                                    std::to_string(j) + " of " + std::to_string(bins) +
                                    " (fewer bins than samples per beat are needed)");
      value[slot] /= count[slot];
      out.mean[j] += value[slot] / out.beats;
    }
  for (int b = 0; b < out.beats; ++b)
    for (std::size_t j = 0; j < nb; ++j) {
      const double d = value[static_cast<std::size_t>(b) * nb + j] - out.mean[j];
      out.rms[j] += d * d / out.beats;
    }
  for (double& r : out.rms) r = std::sqrt(r);
  return out;
}

std::vector<Series> phase_averaged_series(const std::vector<Series>& series, double period_s, int bins, int discard) {
  if (series.empty() || series.front().name != "time_s")
    throw std::invalid_argument("phase_averaged_series: the first series must be time_s");
  std::vector<Series> out;
  for (std::size_t k = 1; k < series.size(); ++k) {
    const PhaseAverage a = phase_average(series.front().values, series[k].values, period_s, bins, discard);
    if (a.beats == 0) return {};
    if (out.empty()) out.push_back({"phase", "", a.phase});
    out.push_back({series[k].name, series[k].unit, a.mean});
    out.push_back({series[k].name + "_rms", series[k].unit, a.rms});
  }
  return out;
}

}  // namespace systole::diagnostics
