#include "solver/geometry/meshing.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace systole::geometry::detail {

namespace {

double orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
}

// > 0 when d is strictly inside the circumcircle of the counter-clockwise triangle abc.
double incircle(const Vec2& a, const Vec2& b, const Vec2& c, const Vec2& d) {
  const double adx = a.x() - d.x(), ady = a.y() - d.y();
  const double bdx = b.x() - d.x(), bdy = b.y() - d.y();
  const double cdx = c.x() - d.x(), cdy = c.y() - d.y();
  const double ad = adx * adx + ady * ady, bd = bdx * bdx + bdy * bdy, cd = cdx * cdx + cdy * cdy;
  return adx * (bdy * cd - bd * cdy) - ady * (bdx * cd - bd * cdx) + ad * (bdx * cdy - bdy * cdx);
}

struct Triangulation {
  std::vector<Vec2> p;
  std::vector<std::array<int, 3>> v;   // counter-clockwise
  std::vector<std::array<int, 3>> nb;  // nb[t][i]: across the edge opposite v[t][i]; -1 none
  std::vector<char> alive;
  std::vector<int> free_slots;
  std::vector<int> mark;  // visit stamp per triangle
  int stamp = 0;

  int new_triangle(int a, int b, int c) {
    int t;
    if (!free_slots.empty()) {
      t = free_slots.back();
      free_slots.pop_back();
      v[t] = {a, b, c};
      nb[t] = {-1, -1, -1};
      alive[t] = 1;
      mark[t] = 0;
    } else {
      t = static_cast<int>(v.size());
      v.push_back({a, b, c});
      nb.push_back({-1, -1, -1});
      alive.push_back(1);
      mark.push_back(0);
    }
    return t;
  }

  int locate(int start, const Vec2& q) const {
    int t = start;
    for (std::size_t steps = 0; steps < 4 * v.size() + 16; ++steps) {
      bool moved = false;
      for (int i = 0; i < 3; ++i) {
        const int a = v[t][(i + 1) % 3], b = v[t][(i + 2) % 3];
        if (orient2d(p[a], p[b], q) < 0 && nb[t][i] >= 0) {
          t = nb[t][i];
          moved = true;
          break;
        }
      }
      if (!moved) return t;
    }
    // Walking can cycle only in degenerate configurations: fall back to a scan.
    for (std::size_t s = 0; s < v.size(); ++s) {
      if (!alive[s]) continue;
      const auto& tv = v[s];
      if (orient2d(p[tv[0]], p[tv[1]], q) >= 0 && orient2d(p[tv[1]], p[tv[2]], q) >= 0 &&
          orient2d(p[tv[2]], p[tv[0]], q) >= 0)
        return static_cast<int>(s);
    }
    throw std::logic_error("delaunay_2d: point location failed");
  }

  int insert(int pi, int start) {
    const Vec2& q = p[pi];
    const int t0 = locate(start, q);
    ++stamp;
    std::vector<int> cavity{t0}, stack{t0};
    mark[t0] = stamp;
    while (!stack.empty()) {
      const int t = stack.back();
      stack.pop_back();
      for (int i = 0; i < 3; ++i) {
        const int n = nb[t][i];
        if (n < 0 || mark[n] == stamp) continue;
        const auto& nv = v[n];
        if (incircle(p[nv[0]], p[nv[1]], p[nv[2]], q) > 0) {
          mark[n] = stamp;
          cavity.push_back(n);
          stack.push_back(n);
        }
      }
    }
    struct Boundary {
      int a, b, outer, outer_slot;
    };
    std::vector<Boundary> boundary;
    for (int t : cavity) {
      for (int i = 0; i < 3; ++i) {
        const int n = nb[t][i];
        if (n >= 0 && mark[n] == stamp) continue;
        int slot = -1;
        if (n >= 0)
          for (int k = 0; k < 3; ++k)
            if (nb[n][k] == t) slot = k;
        boundary.push_back({v[t][(i + 1) % 3], v[t][(i + 2) % 3], n, slot});
      }
    }
    for (int t : cavity) {
      alive[t] = 0;
      free_slots.push_back(t);
    }
    std::vector<int> created;
    created.reserve(boundary.size());
    for (const auto& e : boundary) {
      const int t = new_triangle(e.a, e.b, pi);
      mark[t] = 0;
      nb[t][2] = e.outer;
      if (e.outer >= 0) nb[e.outer][e.outer_slot] = t;
      created.push_back(t);
    }
    for (std::size_t k = 0; k < created.size(); ++k) {
      const int t = created[k];
      const int a = v[t][0], b = v[t][1];
      for (std::size_t j = 0; j < created.size(); ++j) {
        const int s = created[j];
        if (v[s][0] == b) nb[t][0] = s;  // edge (b, p) shared with the triangle starting at b
        if (v[s][1] == a) nb[t][1] = s;  // edge (p, a) shared with the triangle ending at a
      }
    }
    return created.back();
  }
};

}  // namespace

std::vector<Tri> delaunay_2d(const std::vector<Vec2>& points) {
  const int n = static_cast<int>(points.size());
  if (n < 3) return {};
  Vec2 lo = points[0], hi = points[0];
  for (const auto& q : points) {
    lo = lo.cwiseMin(q);
    hi = hi.cwiseMax(q);
  }
  const Vec2 mid = 0.5 * (lo + hi);
  const double span = std::max((hi - lo).maxCoeff(), 1e-9);
  Triangulation dt;
  dt.p = points;
  dt.p.push_back(mid + Vec2(-20 * span, -20 * span));
  dt.p.push_back(mid + Vec2(20 * span, -20 * span));
  dt.p.push_back(mid + Vec2(0, 20 * span));
  int last = dt.new_triangle(n, n + 1, n + 2);

  // Serpentine grid order keeps consecutive points close: walks stay short.
  const double cell = span / std::max(1.0, std::sqrt(static_cast<double>(n)));
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  auto key = [&](int i) {
    const long row = static_cast<long>((points[i].y() - lo.y()) / cell);
    const double x = points[i].x() - lo.x();
    return std::pair<long, double>(row, row % 2 ? -x : x);
  };
  std::sort(order.begin(), order.end(), [&](int a, int b) { return key(a) < key(b); });
  for (int i : order) last = dt.insert(i, last);

  std::vector<Tri> out;
  for (std::size_t t = 0; t < dt.v.size(); ++t) {
    if (!dt.alive[t]) continue;
    const auto& tv = dt.v[t];
    if (tv[0] >= n || tv[1] >= n || tv[2] >= n) continue;
    out.push_back({tv[0], tv[1], tv[2]});
  }
  return out;
}

std::size_t stitch_rings(const Ring& a, const Ring& b, std::vector<Tri>& out) {
  const std::size_t na = a.node.size(), nb = b.node.size();
  // Start b at the node closest in angle to a's first node (modulo 2 pi).
  std::size_t j0 = 0;
  double best = 1e300;
  for (std::size_t j = 0; j < nb; ++j) {
    double d = std::remainder(b.angle[j] - a.angle[0], 2 * M_PI);
    if (std::abs(d) < best) {
      best = std::abs(d);
      j0 = j;
    }
  }
  auto a_angle = [&](std::size_t i) {  // unwrapped
    return a.angle[i % na] + (i >= na ? 2 * M_PI : 0.0);
  };
  auto b_angle = [&](std::size_t j) {
    const std::size_t k = (j0 + j) % nb;
    double ang = b.angle[k] + 2 * M_PI * static_cast<double>((j0 + j) / nb);
    // bring near a's start
    ang -= 2 * M_PI * std::round((b.angle[j0] - a.angle[0]) / (2 * M_PI));
    return ang;
  };
  std::size_t i = 0, j = 0, count = 0;
  while (i < na || j < nb) {
    const bool advance_a = j >= nb || (i < na && a_angle(i + 1) - 0.0 <= b_angle(j + 1));
    const std::int32_t ai = a.node[i % na], bj = b.node[(j0 + j) % nb];
    if (advance_a) {
      out.push_back({ai, a.node[(i + 1) % na], bj});
      ++i;
    } else {
      out.push_back({ai, b.node[(j0 + j + 1) % nb], bj});
      ++j;
    }
    ++count;
  }
  return count;
}

std::size_t close_with_pole(const Ring& a, std::int32_t pole, std::vector<Tri>& out) {
  const std::size_t na = a.node.size();
  for (std::size_t i = 0; i < na; ++i) out.push_back({a.node[i], a.node[(i + 1) % na], pole});
  return na;
}

std::vector<Vec2> hex_lattice(const Vec2& lo, const Vec2& hi, double h) {
  std::vector<Vec2> pts;
  const double dy = h * std::sqrt(3.0) / 2;
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto jitter = [&]() {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return (static_cast<double>(state >> 11) / 9007199254740992.0 - 0.5) * 1e-3 * h;
  };
  int row = 0;
  for (double y = lo.y(); y <= hi.y(); y += dy, ++row) {
    const double x0 = lo.x() + (row % 2 ? 0.5 * h : 0.0);
    for (double x = x0; x <= hi.x(); x += h) pts.emplace_back(x + jitter(), y + jitter());
  }
  return pts;
}

std::vector<double> equal_arclength_stations(const std::vector<double>& param,
                                             const std::vector<double>& arclength, int n) {
  std::vector<double> out(n + 1);
  const double total = arclength.back();
  std::size_t k = 0;
  for (int i = 0; i <= n; ++i) {
    const double target = total * i / n;
    while (k + 2 < arclength.size() && arclength[k + 1] < target) ++k;
    const double s0 = arclength[k], s1 = arclength[k + 1];
    const double w = s1 > s0 ? std::clamp((target - s0) / (s1 - s0), 0.0, 1.0) : 0.0;
    out[i] = param[k] + w * (param[k + 1] - param[k]);
  }
  out.front() = param.front();
  out.back() = param.back();
  return out;
}

}  // namespace systole::geometry::detail
