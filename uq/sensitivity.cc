#include "uq/sensitivity.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "uq/format.h"
#include "uq/random.h"
#include "uq/statistics.h"

namespace systole::uq {
namespace {

using detail::num;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

// Columns of the used rows, centred: fa[j], fb[j], fab[i][j].
struct Columns {
  std::vector<double> fa, fb;
  std::vector<std::vector<double>> fab;
};

struct Estimates {
  double variance;
  std::vector<double> first, total;
};

// Estimators over the rows listed in `rows` (indices into Columns; repeats allowed).
template <class RowAt>
Estimates estimate(const Columns& c, std::size_t m, RowAt row_at) {
  const std::size_t d = c.fab.size();
  Estimates e{0, std::vector<double>(d, 0.0), std::vector<double>(d, 0.0)};
  double s = 0, ss = 0;
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t j = row_at(k);
    s += c.fa[j] + c.fb[j];
  }
  const double mean = s / static_cast<double>(2 * m);
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t j = row_at(k);
    ss += (c.fa[j] - mean) * (c.fa[j] - mean) + (c.fb[j] - mean) * (c.fb[j] - mean);
  }
  e.variance = ss / static_cast<double>(2 * m - 1);
  for (std::size_t i = 0; i < d; ++i) {
    const std::vector<double>& fab = c.fab[i];
    double v1 = 0, vt = 0;
    for (std::size_t k = 0; k < m; ++k) {
      const std::size_t j = row_at(k);
      v1 += c.fb[j] * (fab[j] - c.fa[j]);
      vt += (c.fa[j] - fab[j]) * (c.fa[j] - fab[j]);
    }
    e.first[i] = v1 / static_cast<double>(m) / e.variance;
    e.total[i] = vt / static_cast<double>(2 * m) / e.variance;
  }
  return e;
}

}  // namespace

SobolIndices sobol_indices(const SaltelliLayout& layout, std::span<const double> y,
                           const SobolIndicesOptions& options) {
  if (y.size() != layout.evaluations())
    bad("sobol_indices: " + num(y.size()) + " values given but the Saltelli design has " +
        num(layout.evaluations()) + " evaluations (must be equal: samples * (dimensions + 2) = " +
        num(layout.base_samples()) + " * " + num(layout.blocks_per_row()) + ")");
  if (!(options.confidence > 0.0 && options.confidence < 1.0))
    bad("sobol_indices: confidence = " + num(options.confidence) +
        " is out of range (must be in (0, 1))");
  constexpr std::size_t kMaxResamples = 1000000;
  if (options.bootstrap_resamples > kMaxResamples)
    bad("sobol_indices: bootstrap_resamples = " + num(options.bootstrap_resamples) +
        " is out of range (must be <= " + num(kMaxResamples) + ")");

  const std::size_t n = layout.base_samples(), d = layout.dimensions(), blocks = d + 2;
  SobolIndices out;
  out.rows_total = n;
  out.bootstrap_resamples = options.bootstrap_resamples;
  out.confidence = options.confidence;

  std::vector<std::size_t> used;
  for (std::size_t j = 0; j < n; ++j) {
    std::size_t bad_here = 0;
    for (std::size_t b = 0; b < blocks; ++b)
      if (!std::isfinite(y[j * blocks + b])) ++bad_here;
    out.missing_evaluations += bad_here;
    if (bad_here == 0)
      used.push_back(j);
    else
      out.dropped_rows.push_back(j);
  }
  const std::size_t m = used.size();
  out.rows_used = m;
  out.rows_dropped = n - m;

  const IndexEstimate nan_estimate{kNaN, kNaN, kNaN, kNaN};
  out.first_order.assign(d, nan_estimate);
  out.total.assign(d, nan_estimate);
  out.mean = out.variance = kNaN;
  if (m < 2) {
    out.note = "only " + num(m) + " of " + num(n) +
               " base rows have all their evaluations (need >= 2); indices undefined";
    return out;
  }

  // Centre on the mean of the used A and B values.
  double s = 0;
  for (std::size_t j : used) s += y[j * blocks] + y[j * blocks + 1];
  out.mean = s / static_cast<double>(2 * m);
  Columns c;
  c.fa.resize(m);
  c.fb.resize(m);
  c.fab.assign(d, std::vector<double>(m));
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t base = used[k] * blocks;
    c.fa[k] = y[base] - out.mean;
    c.fb[k] = y[base + 1] - out.mean;
    for (std::size_t i = 0; i < d; ++i) c.fab[i][k] = y[base + 2 + i] - out.mean;
  }

  const Estimates point = estimate(c, m, [](std::size_t k) { return k; });
  out.variance = point.variance;
  if (!(point.variance > 0)) {
    out.note = "the QoI is constant over the " + num(m) + " usable base rows; indices undefined";
    return out;
  }
  for (std::size_t i = 0; i < d; ++i) {
    out.first_order[i].value = point.first[i];
    out.total[i].value = point.total[i];
  }

  const std::size_t R = options.bootstrap_resamples;
  if (R == 0) return out;
  std::vector<std::vector<double>> boot_first(d, std::vector<double>(R)),
      boot_total(d, std::vector<double>(R));
  Rng rng(options.seed);
  std::vector<std::size_t> pick(m);
  std::size_t valid = 0;
  for (std::size_t r = 0; r < R; ++r) {
    for (std::size_t k = 0; k < m; ++k) pick[k] = static_cast<std::size_t>(uniform_below(rng, m));
    const Estimates e = estimate(c, m, [&](std::size_t k) { return pick[k]; });
    if (!(e.variance > 0)) continue;  // a degenerate resample (all rows equal): skip it
    for (std::size_t i = 0; i < d; ++i) {
      boot_first[i][valid] = e.first[i];
      boot_total[i][valid] = e.total[i];
    }
    ++valid;
  }
  if (valid < 2) return out;
  const double lo = (1.0 - options.confidence) / 2.0, hi = (1.0 + options.confidence) / 2.0;
  auto fill = [&](std::vector<double>& reps, IndexEstimate& est) {
    reps.resize(valid);
    double mean = 0;
    for (double v : reps) mean += v;
    mean /= static_cast<double>(valid);
    double ss = 0;
    for (double v : reps) ss += (v - mean) * (v - mean);
    est.std_error = std::sqrt(ss / static_cast<double>(valid - 1));
    std::sort(reps.begin(), reps.end());
    est.ci_low = quantile_sorted(reps, lo);
    est.ci_high = quantile_sorted(reps, hi);
  };
  for (std::size_t i = 0; i < d; ++i) {
    fill(boot_first[i], out.first_order[i]);
    fill(boot_total[i], out.total[i]);
  }
  return out;
}

SobolIndices sobol_indices(const SaltelliLayout& layout, std::span<const std::optional<double>> y,
                           const SobolIndicesOptions& options) {
  const std::vector<double> v = with_nan(y);
  return sobol_indices(layout, std::span<const double>(v), options);
}

}  // namespace systole::uq
