#pragma once
// Probability distributions of uncertain inputs, each defined by its quantile function
// (inverse CDF) so that a design over the unit hypercube maps column by column to the
// physical inputs: x = F^-1(u), u in (0, 1).
//
// Kinds and parameters (all validated; std::invalid_argument names the parameter, its value
// and the allowed range):
//   uniform(a, b)                 a < b, both finite
//   normal(mu, sigma)             mu finite, 0 < sigma < inf
//   lognormal(mu, sigma)          log X ~ normal(mu, sigma): mu finite, 0 < sigma < inf
//   truncated_normal(mu, sigma, a, b)
//                                 normal(mu, sigma) conditioned on a <= X <= b, a < b,
//                                 a may be -inf and b +inf, and the interval must carry
//                                 probability mass representable in double precision.
//
// support() is the smallest closed interval [lo, hi] holding every value the distribution
// can produce (lo/hi may be -inf/+inf): the service compares it to a scenario field's
// allowed range. Every quantile(u) with u in (0, 1) lies in [lo, hi]; lognormal values are
// strictly positive although lo = 0.
#include <cstdint>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "uq/matrix.h"

namespace systole::uq {

// Standard normal CDF Phi(z) and upper tail 1 - Phi(z), accurate to a few ulp in both tails
// (via std::erfc).
double standard_normal_cdf(double z);
double standard_normal_sf(double z);
// Standard normal quantile Phi^-1(p), p in [0, 1] (0 -> -inf, 1 -> +inf): Acklam's rational
// approximation refined by one Halley step on erfc, relative error ~1e-15.
double standard_normal_quantile(double p);

struct Support {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool contains(double x) const { return x >= lo && x <= hi; }
  // True when [lo, hi] is inside the closed interval [min, max] (either may be infinite).
  bool within(double min, double max) const { return lo >= min && hi <= max; }
};

enum class DistributionKind { uniform, normal, lognormal, truncated_normal };

// "uniform", "normal", "lognormal", "truncated_normal"; parse_distribution_kind throws
// std::invalid_argument on an unknown name (listing the allowed ones).
std::string_view to_string(DistributionKind kind);
DistributionKind parse_distribution_kind(std::string_view name);

class Distribution {
 public:
  static Distribution uniform(double a, double b);
  static Distribution normal(double mu, double sigma);
  static Distribution lognormal(double mu, double sigma);  // mu, sigma of log X
  static Distribution truncated_normal(double mu, double sigma, double a, double b);
  // The factory of `kind` with parameters in the order of parameters() below (2 for uniform,
  // normal, lognormal; 4 for truncated_normal); std::invalid_argument on a wrong count.
  static Distribution make(DistributionKind kind, std::span<const double> parameters);

  DistributionKind kind() const { return kind_; }
  // Parameters as given to the factory: uniform {a, b}; normal and lognormal {mu, sigma};
  // truncated_normal {mu, sigma, a, b}.
  std::vector<double> parameters() const;
  // e.g. "truncated_normal(mu=1, sigma=0.5, a=0, b=inf)".
  std::string describe() const;

  Support support() const;
  // Inverse CDF. u must be in [0, 1] (std::invalid_argument otherwise, NaN included);
  // u = 0 and u = 1 give the support bounds (possibly infinite).
  double quantile(double u) const;
  double cdf(double x) const;
  double pdf(double x) const;
  double mean() const;
  double variance() const;
  double std_dev() const;

 private:
  Distribution(DistributionKind kind, double p0, double p1, double p2, double p3);
  DistributionKind kind_;
  double p0_, p1_, p2_, p3_;  // see parameters()
  // truncated normal: standardised bounds and the mass Z = Phi(beta) - Phi(alpha).
  double alpha_ = 0, beta_ = 0, mass_ = 1;
};

// Maps a unit-hypercube design (rows = samples, cols = inputs) to physical values:
// out(r, c) = distributions[c].quantile(unit(r, c)). Requires unit.cols() == distributions.size().
Matrix to_physical(const Matrix& unit, std::span<const Distribution> distributions);

}  // namespace systole::uq
