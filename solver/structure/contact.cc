#include "solver/structure/contact.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::structure {
namespace {

// Voronoi regions of the triangle (vertex, edge, face), tested in turn.
TrianglePoint make_point(const Vec3& a, const Vec3& b, const Vec3& c, double w0, double w1, double w2,
                         bool interior) {
  TrianglePoint r;
  r.w[0] = w0;
  r.w[1] = w1;
  r.w[2] = w2;
  r.p = w0 * a + w1 * b + w2 * c;
  r.interior = interior;
  return r;
}

struct Box {
  Vec3 lo, hi;
};

double box_distance2(const Box& box, const Vec3& x) {
  double d2 = 0;
  for (int k = 0; k < 3; ++k) {
    const double d = std::max({box.lo[k] - x[k], 0.0, x[k] - box.hi[k]});
    d2 += d * d;
  }
  return d2;
}

// Cell key of a point (cells of size h): 21 bits per axis, offset so that negative indices fit.
std::int64_t cell_key(std::int64_t i, std::int64_t j, std::int64_t k) {
  constexpr std::int64_t off = 1 << 20, mask = (1 << 21) - 1;
  return (((i + off) & mask) << 42) | (((j + off) & mask) << 21) | ((k + off) & mask);
}

}  // namespace

// Uniform hash of a body's triangles with cells of at least `radius`: each triangle is entered in
// every cell its bounding box grown by `radius` overlaps, so a point looks up its own cell only.
struct BodyGroup::TriangleHash {
  double radius = 0, inv_h = 0;
  std::vector<Box> boxes;
  Box all{};
  std::vector<std::pair<std::int64_t, std::int32_t>> cells;  // sorted (cell key, triangle)
};

BodyGroup::TriangleHash BodyGroup::hash_triangles(const std::vector<Vec3>& x, const std::vector<geometry::Tri>& tri,
                                                  double radius) {
  TriangleHash h;
  h.radius = radius;
  h.boxes.resize(tri.size());
  h.all = {Vec3::Constant(std::numeric_limits<double>::infinity()), Vec3::Constant(-std::numeric_limits<double>::infinity())};
  double extent = 0;
  for (std::size_t t = 0; t < tri.size(); ++t) {
    Box& bx = h.boxes[t];
    bx.lo = x[tri[t][0]].cwiseMin(x[tri[t][1]]).cwiseMin(x[tri[t][2]]);
    bx.hi = x[tri[t][0]].cwiseMax(x[tri[t][1]]).cwiseMax(x[tri[t][2]]);
    h.all.lo = h.all.lo.cwiseMin(bx.lo);
    h.all.hi = h.all.hi.cwiseMax(bx.hi);
    extent += (bx.hi - bx.lo).maxCoeff();
  }
  // Cells no smaller than the radius (one lookup per node) nor than the mean triangle box (few
  // cells per triangle: a hash with cells of the contact distance costs more to build than
  // the lists save when the triangles are several times larger).
  const double cell = std::max(radius, tri.empty() ? radius : extent / static_cast<double>(tri.size()));
  h.inv_h = 1 / cell;
  for (std::size_t t = 0; t < tri.size(); ++t) {
    const Box& bx = h.boxes[t];
    const Vec3 lo = (bx.lo - Vec3::Constant(radius)) * h.inv_h, hi = (bx.hi + Vec3::Constant(radius)) * h.inv_h;
    for (auto i = static_cast<std::int64_t>(std::floor(lo.x())); i <= static_cast<std::int64_t>(std::floor(hi.x())); ++i)
      for (auto j = static_cast<std::int64_t>(std::floor(lo.y())); j <= static_cast<std::int64_t>(std::floor(hi.y())); ++j)
        for (auto k = static_cast<std::int64_t>(std::floor(lo.z())); k <= static_cast<std::int64_t>(std::floor(hi.z()));
             ++k)
          h.cells.emplace_back(cell_key(i, j, k), static_cast<std::int32_t>(t));
  }
  std::sort(h.cells.begin(), h.cells.end());
  return h;
}

TrianglePoint closest_point_on_triangle(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = x - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return make_point(a, b, c, 1, 0, 0, false);
  const Vec3 bp = x - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return make_point(a, b, c, 0, 1, 0, false);
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double t = d1 / (d1 - d3);
    return make_point(a, b, c, 1 - t, t, 0, false);
  }
  const Vec3 cp = x - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return make_point(a, b, c, 0, 0, 1, false);
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double t = d2 / (d2 - d6);
    return make_point(a, b, c, 1 - t, 0, t, false);
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return make_point(a, b, c, 0, 1 - t, t, false);
  }
  const double inv = 1 / (va + vb + vc);
  const double v = vb * inv, w = vc * inv;
  return make_point(a, b, c, 1 - v - w, v, w, true);
}

BodyGroup::BodyGroup(std::vector<ShellModel> bodies, const ContactOptions& options, int threads)
    : bodies_(std::move(bodies)), options_(options), threads_(threads) {
  auto bad = [](const std::string& field, double v, const char* allowed) {
    std::ostringstream o;
    o << "contact " << field << " = " << v << "; must be " << allowed;
    throw InputError(o.str());
  };
  if (!(options_.distance_mm > 0 && std::isfinite(options_.distance_mm))) bad("distance_mm", options_.distance_mm, "> 0");
  if (!(options_.stiffness_kpa_per_mm >= 0 && std::isfinite(options_.stiffness_kpa_per_mm)))
    bad("stiffness_kpa_per_mm", options_.stiffness_kpa_per_mm, ">= 0");
  if (!(options_.skin_mm > 0 && std::isfinite(options_.skin_mm))) bad("skin_mm", options_.skin_mm, "> 0");
  if (!(options_.damping_ratio >= 0 && options_.damping_ratio <= 2))
    bad("damping_ratio", options_.damping_ratio, "in [0, 2]");
  if (bodies_.empty()) throw InputError("contact: a body group needs at least one body");
  if (threads < 1 || threads > 256)
    throw InputError("body group: threads = " + std::to_string(threads) + " must be in [1, 256]");
  const std::size_t nb = bodies_.size();
  force_.resize(nb);
  row_.resize(nb);
  area_.resize(nb);
  x_build_.resize(nb);
  hash_.resize(nb);
  for (std::size_t k = 0; k < nb; ++k) {
    force_[k].assign(bodies_[k].node_count(), Vec3::Zero());
    row_[k].assign(bodies_[k].node_count(), 0.0);
    area_[k] = bodies_[k].node_areas_mm2();
  }
  if (options_.enabled && nb > 1 && options_.rule == ContactRule::kPenalty) {
    std::vector<TriangleHash> rest;  // stress-free meshes, radius d_c (exclusions)
    for (std::size_t k = 0; k < nb; ++k)
      rest.push_back(hash_triangles(bodies_[k].stress_free_mesh().position_mm, bodies_[k].stress_free_mesh().tri,
                                    options_.distance_mm));
    for (std::size_t a = 0; a < nb; ++a)
      for (std::size_t b = 0; b < nb; ++b) {
        if (a == b) continue;
        Pair p;
        p.a = a;
        p.b = b;
        // Nodes within d_c of the other body in the stress-free meshes take no part (ours).
        build_candidates(p, bodies_[a].stress_free_mesh().position_mm, rest[b]);
        const auto& xa = bodies_[a].stress_free_mesh().position_mm;
        const auto& xb = bodies_[b].stress_free_mesh().position_mm;
        const auto& tri = bodies_[b].stress_free_mesh().tri;
        p.excluded.assign(xa.size(), 0);
        const double dc2 = options_.distance_mm * options_.distance_mm;
        for (std::size_t i = 0; i < xa.size(); ++i)
          for (std::int32_t q = p.offset[i]; q < p.offset[i + 1]; ++q) {
            const auto& t = tri[p.tri[q]];
            const TrianglePoint cp = closest_point_on_triangle(xa[i], xb[t[0]], xb[t[1]], xb[t[2]]);
            if ((xa[i] - cp.p).squaredNorm() < dc2) {
              p.excluded[i] = 1;
              break;
            }
          }
        p.side.assign(xa.size(), 0);
        pairs_.push_back(std::move(p));
      }
    // Force the first build of the candidate lists at the current positions.
    for (std::size_t k = 0; k < nb; ++k)
      x_build_[k].assign(bodies_[k].node_count(), Vec3::Constant(std::numeric_limits<double>::infinity()));
  }
  refresh_contact();
}

// Candidate triangles of body b for every node of body a: triangles whose bounding box is within
// the hash's radius of the node.
void BodyGroup::build_candidates(Pair& pair, const std::vector<Vec3>& xa, const TriangleHash& h) {
  const double r2 = h.radius * h.radius;
  pair.offset.assign(xa.size() + 1, 0);
  pair.tri.clear();
  for (std::size_t n = 0; n < xa.size(); ++n) {
    const Vec3& x = xa[n];
    if (box_distance2(h.all, x) <= r2) {
      const std::int64_t key = cell_key(static_cast<std::int64_t>(std::floor(x.x() * h.inv_h)),
                                        static_cast<std::int64_t>(std::floor(x.y() * h.inv_h)),
                                        static_cast<std::int64_t>(std::floor(x.z() * h.inv_h)));
      auto it = std::lower_bound(h.cells.begin(), h.cells.end(), std::make_pair(key, std::int32_t{-1}));
      for (; it != h.cells.end() && it->first == key; ++it)
        if (box_distance2(h.boxes[it->second], x) <= r2) pair.tri.push_back(it->second);
    }
    pair.offset[n + 1] = static_cast<std::int32_t>(pair.tri.size());
  }
}

void BodyGroup::rehash_body(std::size_t k) {
  hash_[k] = std::make_shared<const TriangleHash>(
      hash_triangles(x_build_[k], bodies_[k].stress_free_mesh().tri, options_.distance_mm + options_.skin_mm));
}

// The candidate lists of a pair (a, b) hold every triangle of b within d_c + skin of a node of a,
// from a's and b's positions at their own last builds; they stay complete for d_c while no node
// of a and no node of b has moved more than skin / 2 since. So only the bodies of which a node
// moved that far are re-hashed, and only the pairs they belong to rebuilt (ours: a fluttering
// leaflet does not re-hash the LV).
void BodyGroup::maybe_rebuild() {
  if (pairs_.empty()) return;
  const double lim2 = 0.25 * options_.skin_mm * options_.skin_mm;
  std::vector<char> moved(bodies_.size(), 0);
  bool any = false;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    const auto& x = bodies_[k].positions_mm();
    for (std::size_t i = 0; i < x.size(); ++i)
      if ((x[i] - x_build_[k][i]).squaredNorm() > lim2) {
        moved[k] = 1;
        any = true;
        break;
      }
  }
  if (!any) return;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    if (!moved[k]) continue;
    x_build_[k] = bodies_[k].positions_mm();
    rehash_body(k);
    ++stats_.body_rebuilds;
  }
  for (Pair& p : pairs_) {
    if (!moved[p.a] && !moved[p.b]) continue;
    build_candidates(p, x_build_[p.a], *hash_[p.b]);
    // A node with no candidate is farther than d_c + skin from b: its side is forgotten (it
    // will be recorded again, from at least d_c away, before it can enter the layer).
    for (std::size_t i = 0; i < p.side.size(); ++i)
      if (p.offset[i] == p.offset[i + 1]) p.side[i] = 0;
  }
  ++stats_.candidate_builds;
}

void BodyGroup::evaluate_contact() {
  const long builds = stats_.candidate_builds, body_rebuilds = stats_.body_rebuilds;
  stats_ = ContactStats{};
  stats_.candidate_builds = builds;
  stats_.body_rebuilds = body_rebuilds;
  for (const Pair& p : pairs_) stats_.candidates += static_cast<long>(p.tri.size());
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    std::fill(force_[k].begin(), force_[k].end(), Vec3::Zero());
    std::fill(row_[k].begin(), row_[k].end(), 0.0);
  }
  const double dc = options_.distance_mm, kappa = options_.stiffness_kpa_per_mm;
  const double zeta = options_.damping_ratio;
  // The stable step of a damped oscillator under central differences is (sqrt(1 + zeta^2) -
  // zeta) times the undamped one: the rows grow by the inverse square.
  const double row_factor = 1 / ((std::sqrt(1 + zeta * zeta) - zeta) * (std::sqrt(1 + zeta * zeta) - zeta));
  for (Pair& p : pairs_) {
    const auto& xa = bodies_[p.a].positions_mm();
    const auto& xb = bodies_[p.b].positions_mm();
    const auto& va = bodies_[p.a].velocities_mm_per_ms();
    const auto& vb = bodies_[p.b].velocities_mm_per_ms();
    const auto& ma = bodies_[p.a].masses_mg();
    const auto& mb = bodies_[p.b].masses_mg();
    const auto& tri = bodies_[p.b].stress_free_mesh().tri;
    for (std::size_t i = 0; i < xa.size(); ++i) {
      if (p.excluded[i] || p.offset[i] == p.offset[i + 1]) continue;
      ++stats_.evaluated_nodes;
      // Closest point of b's surface among the candidates.
      double best = std::numeric_limits<double>::infinity();
      TrianglePoint cp{Vec3::Zero(), {1, 0, 0}, false};
      std::int32_t best_t = -1;
      for (std::int32_t q = p.offset[i]; q < p.offset[i + 1]; ++q) {
        const auto& t = tri[p.tri[q]];
        const TrianglePoint c = closest_point_on_triangle(xa[i], xb[t[0]], xb[t[1]], xb[t[2]]);
        const double d2 = (xa[i] - c.p).squaredNorm();
        if (d2 < best) {
          best = d2;
          cp = c;
          best_t = p.tri[q];
        }
      }
      const auto& t = tri[best_t];
      const Vec3 r = xa[i] - cp.p;
      const double d = std::sqrt(best);
      const Vec3 n = (xb[t[1]] - xb[t[0]]).cross(xb[t[2]] - xb[t[0]]).normalized();
      const double s = r.dot(n);
      const bool clear = cp.interior || std::abs(s) >= 0.5 * d;
      const double k = kappa * area_[p.a][i];
      if (d >= dc) {
        if (clear && s != 0) p.side[i] = s > 0 ? 1 : -1;
        // Near (a candidate) but not in the layer: its stiffness is anticipated in the stable
        // step, so a contact that starts within the next substep does not find it too long.
        row_[p.a][i] += 2 * k * row_factor;
        for (int m = 0; m < 3; ++m) row_[p.b][t[m]] += 2 * k * cp.w[m] * row_factor;
        continue;
      }
      if (p.side[i] == 0 && clear && s != 0) p.side[i] = s > 0 ? 1 : -1;  // started inside the layer
      Vec3 u;
      double sigma = 1;
      if (d > 1e-12 * dc) {
        u = r / d;
        if (p.side[i] != 0 && s * p.side[i] < 0) sigma = -1;
      } else {
        u = p.side[i] < 0 ? Vec3(-n) : n;  // on the surface: push to the remembered side
      }
      const double g = sigma * d;
      const Vec3 e = sigma * u;  // the push's direction on node i
      // The penalty's push k (d_c - g) along e and, with zeta > 0, the viscous layer (ours): a
      // dashpot on the relative velocity of the node and its closest point; its normal part
      // may lessen the push but never turn it into a pull.
      double push = k * (dc - g);
      Vec3 drag = Vec3::Zero();
      if (zeta > 0) {
        Vec3 vp = Vec3::Zero();
        double mp = 0;
        for (int m = 0; m < 3; ++m) {
          vp += cp.w[m] * vb[t[m]];
          mp += cp.w[m] * mb[t[m]];
        }
        const double c = 2 * zeta * std::sqrt(k * ma[i] * mp / (ma[i] + mp));  // mg/ms
        const Vec3 v_rel = va[i] - vp;
        const double vn = v_rel.dot(e);  // > 0: separating
        push = std::max(0.0, push - c * vn);
        drag = -c * (v_rel - vn * e);
      }
      const Vec3 f = push * e + drag;
      force_[p.a][i] += f;
      row_[p.a][i] += 2 * k * row_factor;
      for (int m = 0; m < 3; ++m) {
        force_[p.b][t[m]] -= cp.w[m] * f;
        row_[p.b][t[m]] += 2 * k * cp.w[m] * row_factor;
      }
      ++stats_.active;
      if (g < 0) ++stats_.crossed;
      stats_.min_gap_mm = std::min(stats_.min_gap_mm, g);
      stats_.energy_uj += 0.5 * k * (dc - g) * (dc - g);
    }
  }
  if (pairs_.empty()) return;
  for (std::size_t k = 0; k < bodies_.size(); ++k) bodies_[k].set_contact_loads(force_[k], row_[k]);
}


void BodyGroup::export_state(StateArchive& a, const std::string& prefix) const {
  for (const ShellModel& b : bodies_) {
    const std::string bp = prefix + b.name() + "/";
    a.put_vectors(bp + "x_mm", b.positions_mm());
    a.put_vectors(bp + "v_mm_per_ms", b.velocities_mm_per_ms());
    a.put_scalar(bp + "time_ms", b.time_ms());
  }
  for (std::size_t k = 0; k < x_build_.size(); ++k) a.put_vectors(prefix + bodies_[k].name() + "/x_build_mm", x_build_[k]);
  for (std::size_t p = 0; p < pairs_.size(); ++p)
    a.put(prefix + "pair_" + std::to_string(p) + "/side", std::vector<double>(pairs_[p].side.begin(), pairs_[p].side.end()));
  a.put_scalar(prefix + "candidate_builds", static_cast<double>(stats_.candidate_builds));
}

void BodyGroup::import_state(const StateArchive& a, const std::string& prefix) {
  for (ShellModel& b : bodies_) {
    const std::string bp = prefix + b.name() + "/";
    const long n = static_cast<long>(b.node_count());
    b.set_state(a.get_vectors<Vec3>(bp + "x_mm", n), a.get_vectors<Vec3>(bp + "v_mm_per_ms", n));
    b.set_time_ms(a.scalar(bp + "time_ms"));
  }
  if (!pairs_.empty()) {
    for (std::size_t k = 0; k < x_build_.size(); ++k)
      x_build_[k] = a.get_vectors<Vec3>(prefix + bodies_[k].name() + "/x_build_mm", static_cast<long>(bodies_[k].node_count()));
    for (std::size_t k = 0; k < bodies_.size(); ++k) rehash_body(k);
    for (std::size_t p = 0; p < pairs_.size(); ++p) {
      build_candidates(pairs_[p], x_build_[pairs_[p].a], *hash_[pairs_[p].b]);
      const std::vector<double>& side =
          a.get(prefix + "pair_" + std::to_string(p) + "/side", static_cast<long>(pairs_[p].side.size()));
      for (std::size_t i = 0; i < side.size(); ++i) pairs_[p].side[i] = static_cast<std::int8_t>(side[i]);
    }
  }
  stats_.candidate_builds = static_cast<long>(a.scalar(prefix + "candidate_builds"));
  evaluate_contact();
  for (auto& b : bodies_) b.refresh_forces();
}

void BodyGroup::refresh_contact() {
  maybe_rebuild();
  evaluate_contact();
  for (auto& b : bodies_) b.refresh_forces();
}

double BodyGroup::stable_step_ms() const {
  double dt = std::numeric_limits<double>::infinity();
  for (const auto& b : bodies_) dt = std::min(dt, b.stable_step_ms());
  if (pairs_.empty()) return dt;
  // Contact detection: no node moves more than skin / 2 in one substep (ours), so the layer
  // cannot be crossed within a substep and approaching nodes are seen from outside the layer.
  const double v2 = fastest_node().v2;
  if (v2 > 0) dt = std::min(dt, 0.5 * options_.skin_mm / std::sqrt(v2));
  return dt;
}

BodyGroup::Fastest BodyGroup::fastest_node() const {
  Fastest f;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    const auto& v = bodies_[k].velocities_mm_per_ms();
    for (std::size_t i = 0; i < v.size(); ++i)
      if (v[i].squaredNorm() > f.v2) f = {v[i].squaredNorm(), k, i};
  }
  return f;
}

std::string BodyGroup::stable_step_limiter() const {
  std::size_t body = 0;
  double dt = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < bodies_.size(); ++k)
    if (bodies_[k].stable_step_ms() < dt) {
      dt = bodies_[k].stable_step_ms();
      body = k;
    }
  std::ostringstream m;
  if (!pairs_.empty()) {
    const Fastest f = fastest_node();
    if (f.v2 > 0 && 0.5 * options_.skin_mm / std::sqrt(f.v2) < dt) {
      m << "contact skin: body '" << bodies_[f.body].name() << "' node " << f.node << " moving at " << std::sqrt(f.v2)
        << " m/s";
      return m.str();
    }
  }
  m << "body '" << bodies_[body].name() << "' " << bodies_[body].stable_step_limiter();
  return m.str();
}

// The seed's rule: nodes of different bodies in one cell (side d_c) move together.
void BodyGroup::average_shared_cells() {
  const double inv_h = 1 / options_.distance_mm;
  struct Entry {
    std::int64_t key;
    std::int32_t body, node;
    bool operator<(const Entry& o) const { return key < o.key; }
  };
  std::vector<Entry> entries;
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    const auto& x = bodies_[k].positions_mm();
    for (std::size_t i = 0; i < x.size(); ++i)
      entries.push_back({cell_key(static_cast<std::int64_t>(std::floor(x[i].x() * inv_h)),
                                  static_cast<std::int64_t>(std::floor(x[i].y() * inv_h)),
                                  static_cast<std::int64_t>(std::floor(x[i].z() * inv_h))),
                         static_cast<std::int32_t>(k), static_cast<std::int32_t>(i)});
  }
  std::sort(entries.begin(), entries.end());
  stats_.shared_cells = 0;
  for (std::size_t a = 0; a < entries.size();) {
    std::size_t b = a + 1;
    bool shared = false;
    while (b < entries.size() && entries[b].key == entries[a].key) {
      shared = shared || entries[b].body != entries[a].body;
      ++b;
    }
    if (shared) {
      ++stats_.shared_cells;
      Vec3 p = Vec3::Zero();
      double m = 0;
      for (std::size_t e = a; e < b; ++e) {
        const ShellModel& body = bodies_[entries[e].body];
        if (body.fixed()[entries[e].node]) continue;
        const double mi = body.masses_mg()[entries[e].node];
        p += mi * body.velocities_mm_per_ms()[entries[e].node];
        m += mi;
      }
      if (m > 0)
        for (std::size_t e = a; e < b; ++e) bodies_[entries[e].body].set_node_velocity(entries[e].node, p / m);
    }
    a = b;
  }
}

void BodyGroup::substep(double dt) {
  const auto nb = static_cast<int>(bodies_.size());
  if (threads_ <= 1 || nb < 2) {
    for (auto& b : bodies_) b.begin_substep(dt);
    maybe_rebuild();
    evaluate_contact();
    for (auto& b : bodies_) b.end_substep(dt);
    if (options_.enabled && nb > 1 && options_.rule == ContactRule::kCellAverage) average_shared_cells();
    return;
  }
  // Bodies over threads: whole bodies per thread (dynamic: the largest first in the list is
  // not assumed), contact serial between the two halves. An exception (instability) cannot
  // leave an OpenMP region: it is kept and rethrown after it, the first body's first.
  std::vector<std::exception_ptr> error(bodies_.size());
#pragma omp parallel num_threads(threads_)
  {
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nb; ++k) bodies_[k].begin_substep(dt);
#pragma omp single
    {
      maybe_rebuild();
      evaluate_contact();
    }
#pragma omp for schedule(dynamic, 1)
    for (int k = 0; k < nb; ++k) {
      try {
        bodies_[k].end_substep(dt);
      } catch (...) {
        error[k] = std::current_exception();
      }
    }
  }
  for (const auto& e : error)
    if (e) std::rethrow_exception(e);
  if (options_.enabled && options_.rule == ContactRule::kCellAverage) average_shared_cells();
}

AdvanceStats BodyGroup::advance(double T_ms) {
  AdvanceStats stats;
  if (!(T_ms > 0)) return stats;
  std::vector<double> t_end(bodies_.size());
  for (std::size_t k = 0; k < bodies_.size(); ++k) {
    t_end[k] = bodies_[k].time_ms() + T_ms;
    bodies_[k].begin_advance(T_ms);
  }
  double remaining = T_ms;
  double dt_stable = stable_step_ms();
  long n = std::max(1L, static_cast<long>(std::ceil(remaining / dt_stable)));
  double dt = remaining / n;
  stats.smallest_dt_ms = dt;
  stats.largest_dt_ms = dt;
  std::vector<ShellModel::EnergyWatch> watch(bodies_.size());
  for (std::size_t k = 0; k < bodies_.size(); ++k) watch[k].kinetic_uj = bodies_[k].kinetic_energy_uj();
  int since = 0;
  const int interval = bodies_.front().options().restep_interval;
  while (n > 0) {
    substep(dt);
    remaining -= dt;
    --n;
    ++stats.substeps;
    if (n == 0) break;
    dt_stable = stable_step_ms();
    for (const auto& b : bodies_) b.check_min_step();
    if (dt > dt_stable) {  // re-plan the rest (the Fung law stiffens, contacts start)
      n = std::max(1L, static_cast<long>(std::ceil(remaining / dt_stable)));
      dt = remaining / n;
      stats.smallest_dt_ms = std::min(stats.smallest_dt_ms, dt);
    }
    if (++since < interval) continue;
    since = 0;
    for (std::size_t k = 0; k < bodies_.size(); ++k) bodies_[k].check_energy_growth(watch[k], dt, dt_stable);
  }
  for (std::size_t k = 0; k < bodies_.size(); ++k) bodies_[k].end_advance(t_end[k]);
  return stats;
}

}  // namespace systole::structure
