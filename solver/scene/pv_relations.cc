#include "solver/scene/pv_relations.h"

#include <cmath>
#include <stdexcept>
#include <string>

namespace systole::scene {

EspvrFit fit_espvr(const std::vector<PvPoint>& points) {
  const double n = static_cast<double>(points.size());
  if (points.size() < 2) throw std::invalid_argument("ESPVR: " + std::to_string(points.size()) + " points; need 2");
  double sv = 0, sp = 0;
  for (const PvPoint& q : points) {
    sv += q.volume_ml;
    sp += q.pressure_mmhg;
  }
  const double mv = sv / n, mp = sp / n;
  double svv = 0, svp = 0, spp = 0;
  for (const PvPoint& q : points) {
    svv += (q.volume_ml - mv) * (q.volume_ml - mv);
    svp += (q.volume_ml - mv) * (q.pressure_mmhg - mp);
    spp += (q.pressure_mmhg - mp) * (q.pressure_mmhg - mp);
  }
  if (!(svv > 0)) throw std::invalid_argument("ESPVR: every point has the same volume");
  EspvrFit f;
  f.e_es_mmhg_per_ml = svp / svv;
  f.v0_ml = mv - mp / f.e_es_mmhg_per_ml;
  f.r2 = spp > 0 ? svp * svp / (svv * spp) : 1;
  return f;
}

namespace {

// For a given beta: the least-squares A and the sum of squared residuals.
struct EdpvrTrial {
  double a, ssr;
};
EdpvrTrial edpvr_trial(const std::vector<PvPoint>& pts, double v0, double beta) {
  double su = 0, sup = 0;
  for (const PvPoint& q : pts) {
    const double u = std::expm1(beta * (q.volume_ml - v0));
    su += u * u;
    sup += u * q.pressure_mmhg;
  }
  EdpvrTrial t{su > 0 ? sup / su : 0, 0};
  for (const PvPoint& q : pts) {
    const double r = q.pressure_mmhg - t.a * std::expm1(beta * (q.volume_ml - v0));
    t.ssr += r * r;
  }
  return t;
}

}  // namespace

EdpvrFit fit_edpvr(const std::vector<PvPoint>& points) {
  if (points.size() < 3 || points.front().pressure_mmhg != 0)
    throw std::invalid_argument("EDPVR: needs the unloaded point (0 mmHg) first and 2 loaded points; got " +
                                std::to_string(points.size()) + " points");
  const double v0 = points.front().volume_ml;
  for (std::size_t k = 1; k < points.size(); ++k)
    if (!(points[k].volume_ml > v0))
      throw std::invalid_argument("EDPVR: the point at " + std::to_string(points[k].pressure_mmhg) +
                                  " mmHg has a volume " + std::to_string(points[k].volume_ml) +
                                  " ml not above the unloaded " + std::to_string(v0) + " ml");
  // A scan of log(beta), then golden-section refinement around the best bracket.
  const double lo = std::log(1e-5), hi = std::log(5.0);
  const int n = 400;
  int best = 0;
  double best_ssr = INFINITY;
  for (int k = 0; k <= n; ++k) {
    const double ssr = edpvr_trial(points, v0, std::exp(lo + (hi - lo) * k / n)).ssr;
    if (ssr < best_ssr) best_ssr = ssr, best = k;
  }
  double a = lo + (hi - lo) * std::max(0, best - 1) / n, b = lo + (hi - lo) * std::min(n, best + 1) / n;
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  for (int it = 0; it < 200 && b - a > 1e-14; ++it) {
    const double c = b - g * (b - a), d = a + g * (b - a);
    if (edpvr_trial(points, v0, std::exp(c)).ssr < edpvr_trial(points, v0, std::exp(d)).ssr) b = d;
    else a = c;
  }
  EdpvrFit f;
  f.v0_ml = v0;
  f.beta_per_ml = std::exp(0.5 * (a + b));
  const EdpvrTrial t = edpvr_trial(points, v0, f.beta_per_ml);
  f.a_mmhg = t.a;
  f.rms_mmhg = std::sqrt(t.ssr / static_cast<double>(points.size()));
  return f;
}

}  // namespace systole::scene
