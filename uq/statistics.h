#pragma once
// Descriptive statistics of one quantity of interest (QoI) over a campaign's samples.
//
// Missing values: a failed sample is passed as NaN (or std::nullopt through the overloads
// taking std::optional). Every non-finite value (NaN, +-inf) is EXCLUDED and counted in
// `missing`; nothing is dropped silently. Correlations drop a sample when either the input
// or the QoI is non-finite and report the number of pairs used.
//
// Definitions:
//  - mean = sum y / n; std_dev = sample standard deviation, sqrt(sum (y - mean)^2 / (n - 1))
//    (NaN for n < 2); two-pass algorithm.
//  - percentiles: linear interpolation between order statistics, Hyndman & Fan (1996)
//    definition 7 (the default of R, NumPy and Excel PERCENTILE.INC): for p in [0, 1] and
//    sorted y_(1..n), h = (n - 1) p, Q(p) = y_(floor h + 1) + (h - floor h)(y_(floor h + 2) - y_(floor h + 1)).
//  - histogram: `bins` equal-width bins over [min, max] if given, else Freedman & Diaconis
//    (1981): width h = 2 IQR n^(-1/3), bins = ceil((max - min) / h), capped at max_bins;
//    when IQR = 0 (but max > min) Sturges' ceil(log2 n) + 1 bins. Bins are [e_k, e_k+1), the
//    last one closed. All values equal: one bin [v, v].
//  - Pearson r = sum (x - xbar)(y - ybar) / sqrt(sum (x - xbar)^2 sum (y - ybar)^2);
//    Spearman rho = Pearson r of the ranks, ties given their average rank (fractional
//    ranking). NaN when either variable is constant or fewer than 2 pairs remain.
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "uq/matrix.h"

namespace systole::uq {

// std::nullopt -> NaN, so every function below can take a vector with missing values.
std::vector<double> with_nan(std::span<const std::optional<double>> values);

// Type-7 quantile of an already SORTED, non-empty, all-finite sample; p in [0, 1].
double quantile_sorted(std::span<const double> sorted, double p);
// Type-7 percentiles (p in percent, 0..100) of a sample; non-finite values excluded.
// Throws std::invalid_argument if a p is outside [0, 100] or no finite value remains.
std::vector<double> percentiles(std::span<const double> values, std::span<const double> percent);

struct Histogram {
  std::vector<double> edges;        // bins + 1 increasing edges
  std::vector<std::size_t> counts;  // per bin; sum = number of finite values
  std::string rule;                 // "given", "freedman_diaconis", "sturges" or "single"
};
// bins: 0 = automatic (Freedman–Diaconis); max_bins caps the automatic choice (>= 1).
// Non-finite values are excluded (count them with summarize()).
Histogram histogram(std::span<const double> values, std::size_t bins = 0,
                    std::size_t max_bins = 100);

double pearson(std::span<const double> x, std::span<const double> y);
double spearman(std::span<const double> x, std::span<const double> y);
// Fractional ranks 1..n (ties share their average rank) of an all-finite sample.
std::vector<double> ranks(std::span<const double> values);

struct Correlation {
  double pearson = 0;
  double spearman = 0;
  std::size_t pairs = 0;  // (input, QoI) pairs used: both finite
};
// One Correlation per column of `inputs` (rows = samples; physical values, since Pearson is
// not invariant under the quantile transform while Spearman is) against `qoi`
// (qoi.size() == inputs.rows()).
std::vector<Correlation> input_correlations(const Matrix& inputs, std::span<const double> qoi);

struct StatisticsOptions {
  std::vector<double> percentiles = {5, 25, 50, 75, 95};  // percent
  std::size_t histogram_bins = 0;                         // 0 = Freedman–Diaconis
  std::size_t max_histogram_bins = 100;
};

struct Percentile {
  double percent = 0;
  double value = 0;
};

struct QoiSummary {
  std::size_t total = 0;    // values passed
  std::size_t used = 0;     // finite values, the basis of every statistic below
  std::size_t missing = 0;  // non-finite values excluded (failed samples); total = used + missing
  double mean = 0;
  double std_dev = 0;  // sample (n - 1); NaN if used < 2
  double min = 0;
  double max = 0;
  std::vector<Percentile> percentiles;
  Histogram histogram;
  // When used == 0 every number above is NaN, percentiles hold NaN values and the histogram
  // is empty; summarize() never throws for missing data, only for bad options.
};

QoiSummary summarize(std::span<const double> qoi, const StatisticsOptions& options = {});
QoiSummary summarize(std::span<const std::optional<double>> qoi,
                     const StatisticsOptions& options = {});

}  // namespace systole::uq
