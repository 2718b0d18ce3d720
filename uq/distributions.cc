#include "uq/distributions.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "uq/format.h"

namespace systole::uq {
namespace {

using detail::num;
constexpr double kInf = std::numeric_limits<double>::infinity();

[[noreturn]] void bad(const std::string& message) { throw std::invalid_argument(message); }

double phi(double z) {  // standard normal density; 0 at +-inf
  if (std::isinf(z)) return 0.0;
  return std::exp(-0.5 * z * z) / std::sqrt(2.0 * std::numbers::pi);
}

// Acklam's rational approximation of Phi^-1 on (0, 0.5], |relative error| < 1.15e-9
// (P. J. Acklam, "An algorithm for computing the inverse normal cumulative distribution
// function", 2003), followed by one Halley step on Phi computed with erfc, which brings the
// result to full double precision.
double lower_quantile(double p) {
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                 -2.759285104469687e+02, 1.383577518672690e+02,
                                 -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                 -1.556989798598866e+02, 6.680131188771972e+01,
                                 -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                 -2.400758277161838e+00, -2.549732539343734e+00,
                                 4.374664141464968e+00,  2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01,
                                 2.445134137142996e+00, 3.754408661907416e+00};
  constexpr double p_low = 0.02425;
  double x;
  if (p < p_low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
        ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  } else {
    const double q = p - 0.5;
    const double r = q * q;
    x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
        (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
  }
  // Halley: f(x) = Phi(x) - p, f' = phi(x), f'' = -x phi(x).
  const double e = 0.5 * std::erfc(-x / std::numbers::sqrt2) - p;
  const double u = e * std::sqrt(2.0 * std::numbers::pi) * std::exp(0.5 * x * x);
  if (std::isfinite(u)) x -= u / (1.0 + 0.5 * x * u);
  return x;
}

void require_finite(std::string_view dist, std::string_view name, double v) {
  if (!std::isfinite(v))
    bad(std::string(dist) + ": " + std::string(name) + " = " + num(v) +
        " is out of range (must be finite)");
}
void require_sigma(std::string_view dist, double sigma) {
  if (!(std::isfinite(sigma) && sigma > 0))
    bad(std::string(dist) + ": sigma = " + num(sigma) +
        " is out of range (must be finite and > 0)");
}

}  // namespace

double standard_normal_cdf(double z) { return 0.5 * std::erfc(-z / std::numbers::sqrt2); }
double standard_normal_sf(double z) { return 0.5 * std::erfc(z / std::numbers::sqrt2); }

double standard_normal_quantile(double p) {
  if (!(p >= 0.0 && p <= 1.0))
    bad("standard normal quantile: p = " + num(p) + " is out of range (must be in [0, 1])");
  if (p == 0.0) return -kInf;
  if (p == 1.0) return kInf;
  if (p > 0.5) return -lower_quantile(1.0 - p);  // 1 - p is exact for p >= 0.5
  return lower_quantile(p);
}

std::string_view to_string(DistributionKind kind) {
  switch (kind) {
    case DistributionKind::uniform: return "uniform";
    case DistributionKind::normal: return "normal";
    case DistributionKind::lognormal: return "lognormal";
    case DistributionKind::truncated_normal: return "truncated_normal";
  }
  return "unknown";
}

DistributionKind parse_distribution_kind(std::string_view name) {
  for (auto k : {DistributionKind::uniform, DistributionKind::normal, DistributionKind::lognormal,
                 DistributionKind::truncated_normal})
    if (name == to_string(k)) return k;
  bad("distribution = \"" + std::string(name) +
      "\" is unknown (allowed: uniform, normal, lognormal, truncated_normal)");
}

Distribution::Distribution(DistributionKind kind, double p0, double p1, double p2, double p3)
    : kind_(kind), p0_(p0), p1_(p1), p2_(p2), p3_(p3) {}

Distribution Distribution::uniform(double a, double b) {
  require_finite("uniform", "a", a);
  require_finite("uniform", "b", b);
  if (!(a < b))
    bad("uniform: b = " + num(b) + " is out of range (must be > a = " + num(a) + ")");
  if (!std::isfinite(b - a))
    bad("uniform: b - a = " + num(b - a) + " is out of range (must be finite)");
  return Distribution(DistributionKind::uniform, a, b, 0, 0);
}

Distribution Distribution::normal(double mu, double sigma) {
  require_finite("normal", "mu", mu);
  require_sigma("normal", sigma);
  return Distribution(DistributionKind::normal, mu, sigma, 0, 0);
}

Distribution Distribution::lognormal(double mu, double sigma) {
  require_finite("lognormal", "mu", mu);
  require_sigma("lognormal", sigma);
  return Distribution(DistributionKind::lognormal, mu, sigma, 0, 0);
}

Distribution Distribution::truncated_normal(double mu, double sigma, double a, double b) {
  require_finite("truncated_normal", "mu", mu);
  require_sigma("truncated_normal", sigma);
  if (std::isnan(a) || a == kInf)
    bad("truncated_normal: a = " + num(a) + " is out of range (must be < +inf; -inf allowed)");
  if (std::isnan(b) || b == -kInf)
    bad("truncated_normal: b = " + num(b) + " is out of range (must be > -inf; +inf allowed)");
  if (!(a < b))
    bad("truncated_normal: b = " + num(b) + " is out of range (must be > a = " + num(a) + ")");
  Distribution d(DistributionKind::truncated_normal, mu, sigma, a, b);
  d.alpha_ = (a - mu) / sigma;
  d.beta_ = (b - mu) / sigma;
  // Mass of [alpha, beta], computed in the tail where it is accurate.
  if (d.alpha_ >= 0)
    d.mass_ = standard_normal_sf(d.alpha_) - standard_normal_sf(d.beta_);
  else if (d.beta_ <= 0)
    d.mass_ = standard_normal_cdf(d.beta_) - standard_normal_cdf(d.alpha_);
  else
    d.mass_ = 1.0 - standard_normal_cdf(d.alpha_) - standard_normal_sf(d.beta_);
  if (!(d.mass_ > 0))
    bad("truncated_normal: [a, b] = [" + num(a) + ", " + num(b) +
        "] is out of range (must carry probability mass under normal(mu=" + num(mu) +
        ", sigma=" + num(sigma) + "); it lies " + num(std::min(std::abs(d.alpha_), std::abs(d.beta_))) +
        " sigma from mu)");
  return d;
}

Distribution Distribution::make(DistributionKind kind, std::span<const double> p) {
  const std::size_t expected = kind == DistributionKind::truncated_normal ? 4 : 2;
  if (p.size() != expected)
    bad(std::string(to_string(kind)) + ": parameter count = " + num(p.size()) +
        " is out of range (must be " + num(expected) +
        (kind == DistributionKind::uniform           ? ": a, b)"
         : kind == DistributionKind::truncated_normal ? ": mu, sigma, a, b)"
                                                      : ": mu, sigma)"));
  switch (kind) {
    case DistributionKind::uniform: return uniform(p[0], p[1]);
    case DistributionKind::normal: return normal(p[0], p[1]);
    case DistributionKind::lognormal: return lognormal(p[0], p[1]);
    case DistributionKind::truncated_normal: return truncated_normal(p[0], p[1], p[2], p[3]);
  }
  bad("distribution kind is unknown");
}

std::vector<double> Distribution::parameters() const {
  if (kind_ == DistributionKind::truncated_normal) return {p0_, p1_, p2_, p3_};
  return {p0_, p1_};
}

std::string Distribution::describe() const {
  switch (kind_) {
    case DistributionKind::uniform: return "uniform(a=" + num(p0_) + ", b=" + num(p1_) + ")";
    case DistributionKind::normal: return "normal(mu=" + num(p0_) + ", sigma=" + num(p1_) + ")";
    case DistributionKind::lognormal:
      return "lognormal(mu=" + num(p0_) + ", sigma=" + num(p1_) + ")";
    case DistributionKind::truncated_normal:
      return "truncated_normal(mu=" + num(p0_) + ", sigma=" + num(p1_) + ", a=" + num(p2_) +
             ", b=" + num(p3_) + ")";
  }
  return "unknown";
}

Support Distribution::support() const {
  switch (kind_) {
    case DistributionKind::uniform: return {p0_, p1_};
    case DistributionKind::normal: return {-kInf, kInf};
    case DistributionKind::lognormal: return {0.0, kInf};
    case DistributionKind::truncated_normal: return {p2_, p3_};
  }
  return {};
}

double Distribution::quantile(double u) const {
  if (!(u >= 0.0 && u <= 1.0))
    bad(std::string(to_string(kind_)) + " quantile: u = " + num(u) +
        " is out of range (must be in [0, 1])");
  const Support s = support();
  if (u == 0.0) return s.lo;
  if (u == 1.0) return s.hi;
  switch (kind_) {
    case DistributionKind::uniform: return std::clamp(p0_ + u * (p1_ - p0_), p0_, p1_);
    case DistributionKind::normal: return p0_ + p1_ * standard_normal_quantile(u);
    case DistributionKind::lognormal: return std::exp(p0_ + p1_ * standard_normal_quantile(u));
    case DistributionKind::truncated_normal: {
      // Phi(z) = Phi(alpha) + u Z, or equivalently 1 - Phi(z) = (1 - Phi(beta)) + (1 - u) Z;
      // invert whichever probability is smaller, so tail truncations keep full precision.
      const double p = standard_normal_cdf(alpha_) + u * mass_;
      const double q = standard_normal_sf(beta_) + (1.0 - u) * mass_;
      const double z = p <= q ? standard_normal_quantile(std::min(p, 1.0))
                              : -standard_normal_quantile(std::min(q, 1.0));
      return std::clamp(p0_ + p1_ * z, p2_, p3_);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double Distribution::cdf(double x) const {
  if (std::isnan(x)) return x;
  switch (kind_) {
    case DistributionKind::uniform:
      return std::clamp((x - p0_) / (p1_ - p0_), 0.0, 1.0);
    case DistributionKind::normal: return standard_normal_cdf((x - p0_) / p1_);
    case DistributionKind::lognormal:
      return x <= 0 ? 0.0 : standard_normal_cdf((std::log(x) - p0_) / p1_);
    case DistributionKind::truncated_normal: {
      if (x <= p2_) return 0.0;
      if (x >= p3_) return 1.0;
      const double z = (x - p0_) / p1_;
      const double f = alpha_ >= 0 ? (standard_normal_sf(alpha_) - standard_normal_sf(z)) / mass_
                                   : (standard_normal_cdf(z) - standard_normal_cdf(alpha_)) / mass_;
      return std::clamp(f, 0.0, 1.0);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double Distribution::pdf(double x) const {
  if (std::isnan(x)) return x;
  switch (kind_) {
    case DistributionKind::uniform: return (x >= p0_ && x <= p1_) ? 1.0 / (p1_ - p0_) : 0.0;
    case DistributionKind::normal: return phi((x - p0_) / p1_) / p1_;
    case DistributionKind::lognormal:
      return x <= 0 ? 0.0 : phi((std::log(x) - p0_) / p1_) / (p1_ * x);
    case DistributionKind::truncated_normal:
      return (x < p2_ || x > p3_) ? 0.0 : phi((x - p0_) / p1_) / (p1_ * mass_);
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double Distribution::mean() const {
  switch (kind_) {
    case DistributionKind::uniform: return 0.5 * (p0_ + p1_);
    case DistributionKind::normal: return p0_;
    case DistributionKind::lognormal: return std::exp(p0_ + 0.5 * p1_ * p1_);
    case DistributionKind::truncated_normal:
      return p0_ + p1_ * (phi(alpha_) - phi(beta_)) / mass_;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double Distribution::variance() const {
  switch (kind_) {
    case DistributionKind::uniform: return (p1_ - p0_) * (p1_ - p0_) / 12.0;
    case DistributionKind::normal: return p1_ * p1_;
    case DistributionKind::lognormal:
      return std::expm1(p1_ * p1_) * std::exp(2.0 * p0_ + p1_ * p1_);
    case DistributionKind::truncated_normal: {
      // sigma^2 [1 + (alpha phi(alpha) - beta phi(beta)) / Z - ((phi(alpha) - phi(beta)) / Z)^2]
      const double ta = std::isinf(alpha_) ? 0.0 : alpha_ * phi(alpha_);
      const double tb = std::isinf(beta_) ? 0.0 : beta_ * phi(beta_);
      const double m = (phi(alpha_) - phi(beta_)) / mass_;
      return p1_ * p1_ * (1.0 + (ta - tb) / mass_ - m * m);
    }
  }
  return std::numeric_limits<double>::quiet_NaN();
}

double Distribution::std_dev() const { return std::sqrt(variance()); }

Matrix to_physical(const Matrix& unit, std::span<const Distribution> distributions) {
  if (unit.cols() != distributions.size())
    bad("to_physical: design has " + num(unit.cols()) + " columns but " +
        num(distributions.size()) + " distributions were given (must be equal)");
  Matrix out(unit.rows(), unit.cols());
  for (std::size_t r = 0; r < unit.rows(); ++r)
    for (std::size_t c = 0; c < unit.cols(); ++c) out(r, c) = distributions[c].quantile(unit(r, c));
  return out;
}

}  // namespace systole::uq
