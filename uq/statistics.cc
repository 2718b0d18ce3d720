#include "uq/statistics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>

#include "uq/format.h"

namespace systole::uq {
namespace {

using detail::num;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

std::vector<double> finite_sorted(std::span<const double> values) {
  std::vector<double> v;
  v.reserve(values.size());
  for (double x : values)
    if (std::isfinite(x)) v.push_back(x);
  std::sort(v.begin(), v.end());
  return v;
}

void check_percent(double p) {
  if (!(p >= 0.0 && p <= 100.0))
    bad("percentile = " + num(p) + " is out of range (must be in [0, 100])");
}

// Pairs (x_i, y_i) with both finite.
void finite_pairs(std::span<const double> x, std::span<const double> y, std::vector<double>& fx,
                  std::vector<double>& fy) {
  if (x.size() != y.size())
    bad("correlation: x has " + num(x.size()) + " values but y has " + num(y.size()) +
        " (must be equal)");
  fx.clear();
  fy.clear();
  for (std::size_t i = 0; i < x.size(); ++i)
    if (std::isfinite(x[i]) && std::isfinite(y[i])) {
      fx.push_back(x[i]);
      fy.push_back(y[i]);
    }
}

double pearson_finite(std::span<const double> x, std::span<const double> y) {
  const std::size_t n = x.size();
  if (n < 2) return kNaN;
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / static_cast<double>(n);
  const double my = std::accumulate(y.begin(), y.end(), 0.0) / static_cast<double>(n);
  double sxy = 0, sxx = 0, syy = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = x[i] - mx, dy = y[i] - my;
    sxy += dx * dy;
    sxx += dx * dx;
    syy += dy * dy;
  }
  if (sxx == 0 || syy == 0) return kNaN;
  return std::clamp(sxy / std::sqrt(sxx * syy), -1.0, 1.0);
}

}  // namespace

std::vector<double> with_nan(std::span<const std::optional<double>> values) {
  std::vector<double> out(values.size());
  for (std::size_t i = 0; i < values.size(); ++i) out[i] = values[i].value_or(kNaN);
  return out;
}

double quantile_sorted(std::span<const double> sorted, double p) {
  if (sorted.empty()) bad("quantile: sample is empty (must hold at least 1 finite value)");
  if (!(p >= 0.0 && p <= 1.0)) bad("quantile: p = " + num(p) + " is out of range (must be in [0, 1])");
  const double h = static_cast<double>(sorted.size() - 1) * p;
  const std::size_t lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (h - static_cast<double>(lo)) * (sorted[hi] - sorted[lo]);
}

std::vector<double> percentiles(std::span<const double> values, std::span<const double> percent) {
  for (double p : percent) check_percent(p);
  const std::vector<double> v = finite_sorted(values);
  if (v.empty()) bad("percentiles: no finite value among " + num(values.size()) + " (must be >= 1)");
  std::vector<double> out;
  for (double p : percent) out.push_back(quantile_sorted(v, p / 100.0));
  return out;
}

Histogram histogram(std::span<const double> values, std::size_t bins, std::size_t max_bins) {
  constexpr std::size_t kBinLimit = 100000;
  if (bins > kBinLimit)
    bad("histogram: bins = " + num(bins) + " is out of range (must be <= " + num(kBinLimit) +
        "; 0 = automatic)");
  if (max_bins < 1 || max_bins > kBinLimit)
    bad("histogram: max_bins = " + num(max_bins) + " is out of range (must be in 1.." +
        num(kBinLimit) + ")");
  Histogram h;
  const std::vector<double> v = finite_sorted(values);
  if (v.empty()) return h;
  const double lo = v.front(), hi = v.back();
  const std::size_t n = v.size();
  if (hi == lo) {
    h.edges = {lo, hi};
    h.counts = {n};
    h.rule = "single";
    return h;
  }
  if (bins > 0) {
    h.rule = "given";
  } else {
    const double iqr = quantile_sorted(v, 0.75) - quantile_sorted(v, 0.25);
    if (iqr > 0) {
      const double width = 2.0 * iqr / std::cbrt(static_cast<double>(n));
      const double k = std::ceil((hi - lo) / width);
      bins = k >= static_cast<double>(max_bins) ? max_bins : std::max<std::size_t>(1, static_cast<std::size_t>(k));
      h.rule = "freedman_diaconis";
    } else {
      bins = std::min(max_bins, static_cast<std::size_t>(std::ceil(std::log2(static_cast<double>(n)))) + 1);
      h.rule = "sturges";
    }
  }
  h.edges.resize(bins + 1);
  for (std::size_t k = 0; k <= bins; ++k)
    h.edges[k] = lo + (hi - lo) * (static_cast<double>(k) / static_cast<double>(bins));
  h.edges.back() = hi;
  h.counts.assign(bins, 0);
  for (double x : v) {
    const auto it = std::upper_bound(h.edges.begin(), h.edges.end(), x);
    std::size_t k = static_cast<std::size_t>(it - h.edges.begin());
    k = k == 0 ? 0 : std::min(k - 1, bins - 1);
    ++h.counts[k];
  }
  return h;
}

std::vector<double> ranks(std::span<const double> values) {
  const std::size_t n = values.size();
  std::vector<std::size_t> order(n);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return values[a] < values[b]; });
  std::vector<double> r(n);
  for (std::size_t i = 0; i < n;) {
    std::size_t j = i + 1;
    while (j < n && values[order[j]] == values[order[i]]) ++j;
    const double average = 0.5 * static_cast<double>(i + 1 + j);  // mean of ranks i+1..j
    for (std::size_t k = i; k < j; ++k) r[order[k]] = average;
    i = j;
  }
  return r;
}

double pearson(std::span<const double> x, std::span<const double> y) {
  std::vector<double> fx, fy;
  finite_pairs(x, y, fx, fy);
  return pearson_finite(fx, fy);
}

double spearman(std::span<const double> x, std::span<const double> y) {
  std::vector<double> fx, fy;
  finite_pairs(x, y, fx, fy);
  if (fx.size() < 2) return kNaN;
  return pearson_finite(ranks(fx), ranks(fy));
}

std::vector<Correlation> input_correlations(const Matrix& inputs, std::span<const double> qoi) {
  if (inputs.rows() != qoi.size())
    bad("input_correlations: inputs has " + num(inputs.rows()) + " rows but the QoI has " +
        num(qoi.size()) + " values (must be equal)");
  std::vector<Correlation> out;
  std::vector<double> fx, fy;
  for (std::size_t c = 0; c < inputs.cols(); ++c) {
    const std::vector<double> x = inputs.column(c);
    finite_pairs(x, qoi, fx, fy);
    Correlation k;
    k.pairs = fx.size();
    k.pearson = pearson_finite(fx, fy);
    k.spearman = fx.size() < 2 ? kNaN : pearson_finite(ranks(fx), ranks(fy));
    out.push_back(k);
  }
  return out;
}

QoiSummary summarize(std::span<const double> qoi, const StatisticsOptions& options) {
  for (double p : options.percentiles) check_percent(p);
  QoiSummary s;
  const std::vector<double> v = finite_sorted(qoi);
  s.total = qoi.size();
  s.used = v.size();
  s.missing = s.total - s.used;
  const std::size_t n = v.size();
  if (n == 0) {
    s.mean = s.std_dev = s.min = s.max = kNaN;
    for (double p : options.percentiles) s.percentiles.push_back({p, kNaN});
    histogram(v, options.histogram_bins, options.max_histogram_bins);  // validates options
    return s;
  }
  s.mean = std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(n);
  if (n >= 2) {
    double ss = 0;
    for (double x : v) ss += (x - s.mean) * (x - s.mean);
    s.std_dev = std::sqrt(ss / static_cast<double>(n - 1));
  } else {
    s.std_dev = kNaN;
  }
  s.min = v.front();
  s.max = v.back();
  for (double p : options.percentiles) s.percentiles.push_back({p, quantile_sorted(v, p / 100.0)});
  s.histogram = histogram(v, options.histogram_bins, options.max_histogram_bins);
  return s;
}

QoiSummary summarize(std::span<const std::optional<double>> qoi, const StatisticsOptions& options) {
  const std::vector<double> v = with_nan(qoi);
  return summarize(std::span<const double>(v), options);
}

}  // namespace systole::uq
