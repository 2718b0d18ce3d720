#include "uq/design_checks.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "uq/format.h"

namespace systole::uq {
namespace {

using detail::num;
[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

void check_points(const Matrix& x, std::string_view what) {
  if (x.rows() == 0 || x.cols() == 0)
    bad(std::string(what) + ": design is empty (must have >= 1 row and column)");
  for (double v : x.data())
    if (!(v >= 0.0 && v <= 1.0))
      bad(std::string(what) + ": coordinate = " + num(v) + " is out of range (must be in [0, 1])");
}

}  // namespace

double ks_statistic(std::span<const double> sample, const std::function<double(double)>& cdf) {
  if (sample.empty()) bad("ks_statistic: sample is empty (must have >= 1 value)");
  std::vector<double> f;
  f.reserve(sample.size());
  for (double x : sample) {
    if (!std::isfinite(x)) bad("ks_statistic: value = " + num(x) + " is out of range (must be finite)");
    f.push_back(cdf(x));
  }
  std::sort(f.begin(), f.end());  // F is non-decreasing, so sorting F(x) sorts x
  const double n = static_cast<double>(f.size());
  double d = 0;
  for (std::size_t i = 0; i < f.size(); ++i) {
    d = std::max(d, static_cast<double>(i + 1) / n - f[i]);
    d = std::max(d, f[i] - static_cast<double>(i) / n);
  }
  return d;
}

double ks_statistic_uniform(std::span<const double> sample) {
  return ks_statistic(sample, [](double x) { return std::clamp(x, 0.0, 1.0); });
}

double ks_critical_value(std::size_t n, double alpha) {
  if (n < 1) bad("ks_critical_value: n = 0 is out of range (must be >= 1)");
  if (!(alpha > 0.0 && alpha < 1.0))
    bad("ks_critical_value: alpha = " + num(alpha) + " is out of range (must be in (0, 1))");
  return std::sqrt(-0.5 * std::log(alpha / 2.0)) / std::sqrt(static_cast<double>(n));
}

double kolmogorov_sf(double lambda) {
  if (!(lambda >= 0)) bad("kolmogorov_sf: lambda = " + num(lambda) + " is out of range (must be >= 0)");
  if (lambda == 0) return 1.0;
  constexpr double pi = 3.14159265358979323846;
  if (lambda < 1.18) {
    // Jacobi-theta form of the CDF, fast for small lambda:
    // K(lambda) = sqrt(2 pi) / lambda sum_{k>=1} exp(-(2k - 1)^2 pi^2 / (8 lambda^2)).
    double sum = 0;
    for (int k = 1; k <= 20; ++k) {
      const double t = (2.0 * k - 1.0) * pi / lambda;
      sum += std::exp(-t * t / 8.0);
    }
    return std::clamp(1.0 - std::sqrt(2.0 * pi) / lambda * sum, 0.0, 1.0);
  }
  double sum = 0, sign = 1;
  for (int k = 1; k <= 100; ++k) {
    const double term = std::exp(-2.0 * k * k * lambda * lambda);
    sum += sign * term;
    if (term < 1e-17) break;
    sign = -sign;
  }
  return std::clamp(2.0 * sum, 0.0, 1.0);
}

double centered_l2_discrepancy(const Matrix& x) {
  check_points(x, "centered_l2_discrepancy");
  const std::size_t n = x.rows(), d = x.cols();
  double single = 0;
  for (std::size_t i = 0; i < n; ++i) {
    double p = 1;
    for (std::size_t k = 0; k < d; ++k) {
      const double z = std::abs(x(i, k) - 0.5);
      p *= 1.0 + 0.5 * z - 0.5 * z * z;
    }
    single += p;
  }
  double pair = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto xi = x.row(i);
    double row_sum = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const auto xj = x.row(j);
      double p = 1;
      for (std::size_t k = 0; k < d; ++k)
        p *= 1.0 + 0.5 * std::abs(xi[k] - 0.5) + 0.5 * std::abs(xj[k] - 0.5) -
             0.5 * std::abs(xi[k] - xj[k]);
      row_sum += p;
    }
    pair += row_sum;
  }
  const double nn = static_cast<double>(n);
  const double cd2 = std::pow(13.0 / 12.0, static_cast<double>(d)) - 2.0 / nn * single + pair / (nn * nn);
  return std::sqrt(std::max(cd2, 0.0));
}

double wraparound_l2_discrepancy(const Matrix& x) {
  check_points(x, "wraparound_l2_discrepancy");
  const std::size_t n = x.rows(), d = x.cols();
  double pair = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto xi = x.row(i);
    double row_sum = 0;
    for (std::size_t j = 0; j < n; ++j) {
      const auto xj = x.row(j);
      double p = 1;
      for (std::size_t k = 0; k < d; ++k) {
        const double t = std::abs(xi[k] - xj[k]);
        p *= 1.5 - t * (1.0 - t);
      }
      row_sum += p;
    }
    pair += row_sum;
  }
  const double nn = static_cast<double>(n);
  const double wd2 = -std::pow(4.0 / 3.0, static_cast<double>(d)) + pair / (nn * nn);
  return std::sqrt(std::max(wd2, 0.0));
}

}  // namespace systole::uq
