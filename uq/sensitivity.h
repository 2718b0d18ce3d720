#pragma once
// Variance-based (Sobol') sensitivity indices from the evaluations of a Saltelli design
// (uq/sampling.h), with bootstrap confidence intervals.
//
// Notation: n base rows, d inputs, f_A, f_B, f_ABi the model values at row j of A, B, AB_i
// (AB_i = A with column i from B); m = rows used (below); ybar, V = mean and sample variance
// (denominator 2m - 1) of the 2m values f_A, f_B. The outputs are centred, y <- y - ybar,
// before the first-order estimator, which is not shift-invariant in finite samples (centring
// removes a zero-mean noise term ybar * mean(f_ABi - f_A)).
//   first order (Saltelli et al. 2010, eq. in Table 2 for V[E(Y|X_i)]):
//       S_i  = [ (1/m) sum_j f_B,j (f_ABi,j - f_A,j) ] / V
//   total effect (Jansen 1999; recommended in Saltelli et al. 2010, Table 2):
//       ST_i = [ (1/(2m)) sum_j (f_A,j - f_ABi,j)^2 ] / V
// Estimates are not clipped to [0, 1]: small negative values of S_i mean "zero within noise".
//
// Missing values: a failed evaluation is NaN (or std::nullopt); every non-finite value counts
// as missing. A row j is used only if all d + 2 of its evaluations (A, B, AB_0..AB_d-1) are
// finite; otherwise the whole row group is dropped, and rows_used / rows_dropped /
// missing_evaluations report it.
//
// Bootstrap (Efron & Tibshirani 1993): `resamples` times,
// draw m rows with replacement from the used rows (std::mt19937_64 seeded with
// options.seed, platform-independent), recompute V, S_i and ST_i (same centring constant); the
// interval is the percentile interval [Q((1 - c)/2), Q((1 + c)/2)] of the replicates
// (type-7 quantiles), std_error their standard deviation. Rows are resampled as i.i.d.: with a
// scrambled Sobol' base the true error is smaller, so the intervals are conservative
// (measured on Ishigami: uq/README.md).
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "uq/sampling.h"

namespace systole::uq {

struct SobolIndicesOptions {
  std::size_t bootstrap_resamples = 1000;  // 0..1'000'000; 0 = no intervals (NaN)
  double confidence = 0.95;                // in (0, 1)
  std::uint64_t seed = 0;                  // bootstrap seed
};

struct IndexEstimate {
  double value = 0;      // estimate from all used rows
  double ci_low = 0;     // bootstrap percentile interval (NaN without resamples)
  double ci_high = 0;
  double std_error = 0;  // bootstrap standard deviation (NaN without resamples)
};

struct SobolIndices {
  std::size_t rows_total = 0;           // n
  std::size_t rows_used = 0;            // m: rows whose d + 2 evaluations are all finite
  std::size_t rows_dropped = 0;         // n - m
  std::size_t missing_evaluations = 0;  // non-finite evaluations among the n (d + 2)
  std::vector<std::size_t> dropped_rows;
  double mean = 0;      // ybar over the used A and B evaluations
  double variance = 0;  // V
  std::vector<IndexEstimate> first_order;  // S_i, i = 0..d-1
  std::vector<IndexEstimate> total;        // ST_i
  std::size_t bootstrap_resamples = 0;
  double confidence = 0;
  // Empty when the estimates are valid; otherwise why they are NaN (fewer than 2 usable rows,
  // or a QoI that is constant over them).
  std::string note;
};

// y: one value per evaluation, in the evaluation order of `layout` (y.size() ==
// layout.evaluations()).
SobolIndices sobol_indices(const SaltelliLayout& layout, std::span<const double> y,
                           const SobolIndicesOptions& options = {});
SobolIndices sobol_indices(const SaltelliLayout& layout, std::span<const std::optional<double>> y,
                           const SobolIndicesOptions& options = {});

}  // namespace systole::uq
