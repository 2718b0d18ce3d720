#include "solver/diagnostics/phase_average.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace systole::diagnostics {
namespace {
// Where a sample at t_s falls: beat k (0-based, [kT, (k+1)T), a sample within 1e-9 s below a
// beat's start counted in it) and phase bin j; a sample on a bin's lower edge (to round-off)
// belongs to that bin.
struct PhaseSlot {
  long beat;
  std::size_t bin;
};
PhaseSlot phase_slot(double t_s, double period_s, int bins) {
  const double beats_in = t_s / period_s;
  const long k = static_cast<long>(std::floor(beats_in + 1e-9 / period_s));
  const double phase = std::max(0.0, beats_in - static_cast<double>(k));
  return {k, std::min(static_cast<std::size_t>(bins - 1), static_cast<std::size_t>(std::floor(phase * bins + 1e-9)))};
}
}  // namespace

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
    const PhaseSlot p = phase_slot(time_s[i], period_s, bins);
    if (p.beat < discard || p.beat >= whole) continue;
    const std::size_t slot = static_cast<std::size_t>(p.beat - discard) * nb + p.bin;
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

FieldPhaseAverage::FieldPhaseAverage(std::size_t size, double period_s, int bins, int discard)
    : size_(size), period_s_(period_s), bins_(bins), discard_(discard) {
  if (!(period_s > 0)) throw std::invalid_argument("FieldPhaseAverage: period " + std::to_string(period_s) + " s must be > 0");
  if (bins < 1) throw std::invalid_argument("FieldPhaseAverage: bins = " + std::to_string(bins) + " must be >= 1");
  const std::size_t n = static_cast<std::size_t>(bins) * size;
  sum_.assign(n, 0.0);
  s1_.assign(n, 0.0);
  s2_.assign(n, 0.0);
  count_.assign(static_cast<std::size_t>(bins), 0.0);
  folded_.assign(static_cast<std::size_t>(bins), 0);
}

void FieldPhaseAverage::fold() {
  if (beat_ >= discard_)
    for (std::size_t j = 0; j < count_.size(); ++j) {
      if (count_[j] == 0) continue;
      for (std::size_t i = 0; i < size_; ++i) {
        const double m = sum_[j * size_ + i] / count_[j];
        s1_[j * size_ + i] += m;
        s2_[j * size_ + i] += m * m;
      }
      ++folded_[j];
    }
  std::fill(sum_.begin(), sum_.end(), 0.0);
  std::fill(count_.begin(), count_.end(), 0.0);
}

void FieldPhaseAverage::add(double t_s, const std::vector<double>& values) {
  if (values.size() != size_)
    throw std::invalid_argument("FieldPhaseAverage: " + std::to_string(values.size()) + " values, expected " +
                                std::to_string(size_));
  const PhaseSlot p = phase_slot(t_s, period_s_, bins_);
  if (p.beat != beat_) {
    if (beat_ >= 0) fold();
    beat_ = p.beat;
  }
  const std::size_t j = p.bin;
  for (std::size_t i = 0; i < size_; ++i) sum_[j * size_ + i] += values[i];
  count_[j] += 1;
}

std::vector<double> FieldPhaseAverage::mean(int j) const {
  const auto b = static_cast<std::size_t>(j);
  std::vector<double> m(size_, 0.0);
  if (folded_.at(b) > 0)
    for (std::size_t i = 0; i < size_; ++i) m[i] = s1_[b * size_ + i] / folded_[b];
  return m;
}

std::vector<double> FieldPhaseAverage::rms(int j) const {
  const auto b = static_cast<std::size_t>(j);
  std::vector<double> r(size_, 0.0);
  if (folded_.at(b) > 0)
    for (std::size_t i = 0; i < size_; ++i) {
      const double m = s1_[b * size_ + i] / folded_[b];
      r[i] = std::sqrt(std::max(0.0, s2_[b * size_ + i] / folded_[b] - m * m));
    }
  return r;
}

void FieldPhaseAverage::export_state(StateArchive& archive, const std::string& prefix) const {
  archive.put_scalar(prefix + "beat", static_cast<double>(beat_));
  archive.put(prefix + "sum", sum_);
  archive.put(prefix + "count", count_);
  archive.put(prefix + "s1", s1_);
  archive.put(prefix + "s2", s2_);
  archive.put(prefix + "folded", std::vector<double>(folded_.begin(), folded_.end()));
}

void FieldPhaseAverage::import_state(const StateArchive& archive, const std::string& prefix) {
  const auto n = static_cast<long>(sum_.size()), nb = static_cast<long>(bins_);
  beat_ = static_cast<long>(archive.scalar(prefix + "beat"));
  sum_ = archive.get(prefix + "sum", n);
  count_ = archive.get(prefix + "count", nb);
  s1_ = archive.get(prefix + "s1", n);
  s2_ = archive.get(prefix + "s2", n);
  const std::vector<double>& f = archive.get(prefix + "folded", nb);
  for (std::size_t j = 0; j < folded_.size(); ++j) folded_[j] = static_cast<int>(f[j]);
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
