#include "solver/geometry/quality.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "solver/core/errors.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/topology.h"

namespace systole::geometry {

namespace {

std::string at(const Vec3& p) {
  std::ostringstream s;
  s.precision(4);
  s << "(" << p.x() << ", " << p.y() << ", " << p.z() << ") mm";
  return s.str();
}

// Collects issues of one kind: counts them and keeps the first example.
struct Tally {
  Tally(std::string c, std::string b) : check(std::move(c)), body(std::move(b)) {}
  std::string check, body;
  std::size_t count = 0;
  std::string first;
  void add(const std::string& example) {
    if (count++ == 0) first = example;
  }
  void flush(std::vector<QualityIssue>& out, const std::string& what) const {
    if (count == 0) return;
    out.push_back({check, body,
                   "body '" + body + "': " + std::to_string(count) + " " + what + "; first: " + first});
  }
};

double orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a);
}

// True if segment pq crosses the interior of triangle abc. Signed volumes within `eps` of
// zero count as zero (touching, coplanar): round-off never reports a crossing, and coplanar
// overlaps are not detected (a documented limitation).
bool segment_crosses(const Vec3& p, const Vec3& q, const Vec3& a, const Vec3& b, const Vec3& c, double eps) {
  const double o1 = orient3d(a, b, c, p), o2 = orient3d(a, b, c, q);
  if (!((o1 > eps && o2 < -eps) || (o1 < -eps && o2 > eps))) return false;
  const double s1 = orient3d(p, q, a, b), s2 = orient3d(p, q, b, c), s3 = orient3d(p, q, c, a);
  return (s1 > eps && s2 > eps && s3 > eps) || (s1 < -eps && s2 < -eps && s3 < -eps);
}

bool triangles_cross(const Vec3 t1[3], const Vec3 t2[3]) {
  double l = 0;
  for (int k = 0; k < 3; ++k)
    l = std::max({l, (t1[k] - t1[(k + 1) % 3]).norm(), (t2[k] - t2[(k + 1) % 3]).norm()});
  const double eps = 1e-10 * l * l * l;
  for (int k = 0; k < 3; ++k) {
    if (segment_crosses(t1[k], t1[(k + 1) % 3], t2[0], t2[1], t2[2], eps)) return true;
    if (segment_crosses(t2[k], t2[(k + 1) % 3], t1[0], t1[1], t1[2], eps)) return true;
  }
  return false;
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection, 5.1.5).
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

struct Cell {
  std::int64_t i, j, k;
};
std::int64_t cell_key(std::int64_t i, std::int64_t j, std::int64_t k) {
  return ((i & 0x1FFFFF) << 42) | ((j & 0x1FFFFF) << 21) | (k & 0x1FFFFF);
}

double triangle_angle_deg(const Vec3& a, const Vec3& b, const Vec3& c) {  // angle at a
  const Vec3 u = b - a, v = c - a;
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0 || nv == 0) return 0;
  return std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * 180.0 / M_PI;
}

std::uint32_t allowed_tissues(std::uint32_t bit) {
  auto m = [](Tissue t) { return 1u << static_cast<int>(t); };
  switch (bit) {
    case kHisBundle:
    case kLvApex:
    case kLvApexRing:
    case kLvBaseRing:
      return m(Tissue::kLvMyocardium);
    case kBachmannBundle:
    case kPvOstiumLeftSuperior:
    case kPvOstiumLeftInferior:
    case kPvOstiumRightSuperior:
    case kPvOstiumRightInferior:
      return m(Tissue::kLaMyocardium) | m(Tissue::kVeinOstium);
    case kOutflow:
      return m(Tissue::kAorticWall);
    case kFreeEdge:
      return m(Tissue::kMitralLeaflet) | m(Tissue::kAorticLeaflet);
    case kMitralAnnulus:
      return m(Tissue::kLaMyocardium) | m(Tissue::kMitralLeaflet) | m(Tissue::kValvularPlane);
    case kAorticAnnulus:
      return m(Tissue::kAorticWall) | m(Tissue::kAorticLeaflet) | m(Tissue::kValvularPlane);
    default:
      return 0xFFFFFFFFu;
  }
}

}  // namespace

std::vector<QualityIssue> check_body(const TriMesh& mesh, const CheckOptions& o) {
  std::vector<QualityIssue> out;
  const std::string& body = mesh.name;
  try {
    mesh.check_arrays();
  } catch (const std::logic_error& e) {
    out.push_back({"arrays", body, e.what()});
    return out;
  }
  Tally nonfinite{"non_finite_position", body};
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if (!mesh.position_mm[i].allFinite()) nonfinite.add("node " + std::to_string(i));
  nonfinite.flush(out, "node(s) with a non-finite position");
  if (!out.empty()) return out;

  const EdgeTopology topo(mesh);
  Tally nonmanifold{"non_manifold_edge", body}, orientation{"inconsistent_orientation", body};
  for (std::size_t e = 0; e < topo.edge_count(); ++e) {
    const auto [a, b] = topo.edge[e];
    const int nf = topo.face_count_of(e);
    const std::string where = "edge between nodes " + std::to_string(a) + " and " +
                              std::to_string(b) + " at " +
                              at(0.5 * (mesh.position_mm[a] + mesh.position_mm[b]));
    if (nf > 2) nonmanifold.add(where + " is shared by " + std::to_string(nf) + " triangles");
    if (nf == 2) {
      const auto f0 = topo.edge_face[topo.edge_face_offset[e]];
      const auto f1 = topo.edge_face[topo.edge_face_offset[e] + 1];
      if (EdgeTopology::traverses_forward(mesh, f0, a, b) ==
          EdgeTopology::traverses_forward(mesh, f1, a, b))
        orientation.add(where + ": triangles " + std::to_string(f0) + " and " + std::to_string(f1) +
                        " traverse it in the same direction");
    }
  }
  nonmanifold.flush(out, "non-manifold edge(s) (more than two triangles share an edge)");
  orientation.flush(out, "edge(s) with inconsistent orientation (neighbouring normals disagree)");

  Tally degenerate{"degenerate_triangle", body}, inverted{"inverted_triangle", body};
  Tally fibre{"bad_fibre", body}, thickness{"bad_thickness", body};
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto& [a, b, c] = mesh.tri[t];
    const Vec3 &pa = mesh.position_mm[a], &pb = mesh.position_mm[b], &pc = mesh.position_mm[c];
    const double min_angle = std::min({triangle_angle_deg(pa, pb, pc), triangle_angle_deg(pb, pc, pa),
                                       triangle_angle_deg(pc, pa, pb)});
    const bool degen = a == b || b == c || a == c || mesh.area_mm2(t) <= 0 ||
                       min_angle < o.degenerate_min_angle_deg;
    if (degen) {
      std::ostringstream s;
      s.precision(3);
      s << "triangle " << t << " at " << at(mesh.centroid(t)) << " has area " << mesh.area_mm2(t)
        << " mm^2 and smallest angle " << min_angle << " deg (minimum "
        << o.degenerate_min_angle_deg << ")";
      degenerate.add(s.str());
      continue;
    }
    // Inverted (folded over): its normal turns by more than 150 degrees from an edge
    // neighbour's across a consistently oriented edge (a node dragged across an edge).
    const Vec3 n = mesh.unit_normal(t);
    for (int k = 0; k < 3; ++k) {
      const auto e = topo.face_edge[t][k];
      if (topo.face_count_of(e) != 2) continue;
      const auto f0 = topo.edge_face[topo.edge_face_offset[e]];
      const auto f1 = topo.edge_face[topo.edge_face_offset[e] + 1];
      const auto other = static_cast<std::size_t>(f0) == t ? f1 : f0;
      const auto [ea, eb] = topo.edge[e];
      if (EdgeTopology::traverses_forward(mesh, t, ea, eb) == EdgeTopology::traverses_forward(mesh, other, ea, eb))
        continue;  // reported as inconsistent orientation
      if (n.dot(mesh.unit_normal(other)) < -0.866) {
        inverted.add("triangle " + std::to_string(t) + " at " + at(mesh.centroid(t)) +
                     " faces against its neighbour " + std::to_string(other));
        break;
      }
    }
    const Vec3& f = mesh.fibre[t];
    if (!f.allFinite() || std::abs(f.norm() - 1) > 1e-6 || std::abs(f.dot(n)) > 1e-6)
      fibre.add("triangle " + std::to_string(t) + " at " + at(mesh.centroid(t)) +
                " has fibre |f| = " + std::to_string(f.norm()) +
                ", f.n = " + std::to_string(f.dot(n)) + " (need a unit tangent)");
    if (!(mesh.thickness_mm[t] > 0) || !std::isfinite(mesh.thickness_mm[t]))
      thickness.add("triangle " + std::to_string(t) + " thickness_mm = " +
                    std::to_string(mesh.thickness_mm[t]) + " (must be > 0)");
  }
  degenerate.flush(out, "degenerate triangle(s)");
  inverted.flush(out, "inverted (folded-over) triangle(s)");
  fibre.flush(out, "triangle(s) with a bad fibre direction");
  thickness.flush(out, "triangle(s) with a bad thickness");

  // Holes and openings.
  const auto loops = boundary_loops(mesh, topo);
  Tally hole{"hole", body};
  int loops_in_plane = 0;
  bool all_in_plane = true;
  for (const auto& loop : loops) {
    double off = 0;
    Vec3 worst = mesh.position_mm[loop[0]];
    for (auto v : loop) {
      const double d = std::abs(mesh.position_mm[v].z() - o.plane_z_mm);
      if (d > off) {
        off = d;
        worst = mesh.position_mm[v];
      }
    }
    const bool in_plane = off <= o.plane_tolerance_mm;
    loops_in_plane += in_plane;
    all_in_plane = all_in_plane && in_plane;
    if (!in_plane && mesh.kind == BodyKind::kChamber)
      hole.add("open boundary loop of " + std::to_string(loop.size()) + " edges reaching " +
               at(worst) + ", " + std::to_string(off) + " mm off the valvular plane z = " +
               std::to_string(o.plane_z_mm));
  }
  hole.flush(out, "hole(s) in a chamber that must be closed by the valvular plane");
  if (mesh.kind == BodyKind::kVessel && loops_in_plane == 0)
    out.push_back({"hole", body, "body '" + body + "': vessel has no opening in the valvular plane"});
  if (mesh.kind == BodyKind::kChamber && all_in_plane && out.empty()) {
    const double v = cavity_volume_ml(mesh, o.plane_z_mm);
    if (v <= 0)
      out.push_back({"inverted_body", body,
                     "body '" + body + "': normals point out of the cavity (closed volume " +
                         std::to_string(v) + " ml <= 0); they must point into the blood"});
  }

  // Tags.
  std::vector<std::uint32_t> node_tissues(mesh.node_count(), 0);
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t)
    for (auto v : mesh.tri[t]) node_tissues[v] |= 1u << static_cast<int>(mesh.tissue[t]);
  Tally unknown{"bad_tag", body}, off_plane{"bad_tag", body}, wrong{"bad_tag", body};
  std::size_t anchors = 0;
  for (std::size_t i = 0; i < mesh.node_count(); ++i) {
    const std::uint32_t r = mesh.region[i];
    if (r & ~kAllRegionBits)
      unknown.add("node " + std::to_string(i) + " carries bits " + region_list(r & ~kAllRegionBits));
    if (r & kAnchor) {
      ++anchors;
      const double d = std::abs(mesh.position_mm[i].z() - o.plane_z_mm);
      const double above = o.plane_z_mm - mesh.position_mm[i].z();
      const bool on_crown = (r & kAorticAnnulus) && above >= -o.plane_tolerance_mm &&
                            above <= o.aortic_crown_height_mm + o.plane_tolerance_mm;
      if (d > o.plane_tolerance_mm && !on_crown)
        off_plane.add("anchor node " + std::to_string(i) + " at " + at(mesh.position_mm[i]) + " is " +
                      std::to_string(d) + " mm off the valvular plane");
    }
    for (int b = 1; b < kRegionBitCount; ++b) {
      const std::uint32_t bit = 1u << b;
      if (!(r & bit) || !node_tissues[i]) continue;
      if (!(node_tissues[i] & allowed_tissues(bit)))
        wrong.add("node " + std::to_string(i) + " tagged " +
                  std::string(region_name(static_cast<Region>(bit))) + " lies on " +
                  std::string(tissue_name(static_cast<Tissue>(std::countr_zero(node_tissues[i])))) +
                  " tissue");
    }
  }
  unknown.flush(out, "node(s) with unknown region bits (bad tags)");
  off_plane.flush(out, "anchor node(s) off the valvular plane (bad tags)");
  wrong.flush(out, "node(s) with a region tag on the wrong tissue (bad tags)");
  if (mesh.kind != BodyKind::kRigid && anchors == 0 && mesh.node_count() > 0)
    out.push_back({"bad_tag", body,
                   "body '" + body + "': no node is tagged anchor; every deformable body must be "
                   "anchored to the valvular plane (bad tags)"});
  return out;
}

std::vector<QualityIssue> check_intersections(const std::vector<const TriMesh*>& bodies) {
  struct Ref {
    std::int32_t body, tri;
  };
  std::vector<Ref> refs;
  double extent_sum = 0;
  Vec3 lo = Vec3::Constant(1e300);
  for (std::size_t b = 0; b < bodies.size(); ++b)
    for (std::size_t t = 0; t < bodies[b]->triangle_count(); ++t) {
      refs.push_back({static_cast<std::int32_t>(b), static_cast<std::int32_t>(t)});
      Vec3 tl = Vec3::Constant(1e300), th = Vec3::Constant(-1e300);
      for (auto v : bodies[b]->tri[t]) {
        tl = tl.cwiseMin(bodies[b]->position_mm[v]);
        th = th.cwiseMax(bodies[b]->position_mm[v]);
      }
      lo = lo.cwiseMin(tl);
      extent_sum += (th - tl).maxCoeff();
    }
  if (refs.empty()) return {};
  const double cell = std::max(2.0 * extent_sum / static_cast<double>(refs.size()), 1e-6);
  auto box = [&](const Ref& r, Vec3& tl, Vec3& th) {
    tl = Vec3::Constant(1e300);
    th = Vec3::Constant(-1e300);
    for (auto v : bodies[r.body]->tri[r.tri]) {
      tl = tl.cwiseMin(bodies[r.body]->position_mm[v]);
      th = th.cwiseMax(bodies[r.body]->position_mm[v]);
    }
  };
  auto idx = [&](double x, double x0) { return static_cast<std::int64_t>(std::floor((x - x0) / cell)); };
  std::vector<std::pair<std::int64_t, std::int32_t>> entries;
  for (std::size_t r = 0; r < refs.size(); ++r) {
    Vec3 tl, th;
    box(refs[r], tl, th);
    for (auto i = idx(tl.x(), lo.x()); i <= idx(th.x(), lo.x()); ++i)
      for (auto j = idx(tl.y(), lo.y()); j <= idx(th.y(), lo.y()); ++j)
        for (auto k = idx(tl.z(), lo.z()); k <= idx(th.z(), lo.z()); ++k)
          entries.emplace_back(cell_key(i, j, k), static_cast<std::int32_t>(r));
  }
  std::sort(entries.begin(), entries.end());
  std::vector<std::vector<std::size_t>> count(bodies.size(), std::vector<std::size_t>(bodies.size(), 0));
  std::vector<std::vector<std::string>> first(bodies.size(), std::vector<std::string>(bodies.size()));
  for (std::size_t s = 0; s < entries.size();) {
    std::size_t e = s;
    while (e < entries.size() && entries[e].first == entries[s].first) ++e;
    for (std::size_t p = s; p < e; ++p)
      for (std::size_t q = p + 1; q < e; ++q) {
        const Ref &r1 = refs[entries[p].second], &r2 = refs[entries[q].second];
        Vec3 l1, h1, l2, h2;
        box(r1, l1, h1);
        box(r2, l2, h2);
        if ((l1.array() > h2.array()).any() || (l2.array() > h1.array()).any()) continue;
        // Test each pair once: in the cell holding the low corner of the boxes' overlap.
        const Vec3 ol = l1.cwiseMax(l2);
        if (cell_key(idx(ol.x(), lo.x()), idx(ol.y(), lo.y()), idx(ol.z(), lo.z())) != entries[s].first)
          continue;
        const TriMesh &m1 = *bodies[r1.body], &m2 = *bodies[r2.body];
        const auto &t1 = m1.tri[r1.tri], &t2 = m2.tri[r2.tri];
        const Vec3 p1[3] = {m1.position_mm[t1[0]], m1.position_mm[t1[1]], m1.position_mm[t1[2]]};
        const Vec3 p2[3] = {m2.position_mm[t2[0]], m2.position_mm[t2[1]], m2.position_mm[t2[2]]};
        bool shared = false;
        for (int i = 0; i < 3 && !shared; ++i)
          for (int j = 0; j < 3 && !shared; ++j)
            shared = r1.body == r2.body ? t1[i] == t2[j] : p1[i] == p2[j];
        if (shared || !triangles_cross(p1, p2)) continue;
        const auto b1 = std::min(r1.body, r2.body), b2 = std::max(r1.body, r2.body);
        if (count[b1][b2]++ == 0)
          first[b1][b2] = "triangle " + std::to_string(r1.tri) + " of '" + m1.name + "' crosses triangle " +
                          std::to_string(r2.tri) + " of '" + m2.name + "' near " + at((p1[0] + p2[0]) / 2);
      }
    s = e;
  }
  std::vector<QualityIssue> out;
  for (std::size_t a = 0; a < bodies.size(); ++a)
    for (std::size_t b = a; b < bodies.size(); ++b) {
      if (!count[a][b]) continue;
      const std::string what = a == b ? "body '" + bodies[a]->name + "' intersects itself"
                                      : "bodies '" + bodies[a]->name + "' and '" + bodies[b]->name + "' intersect";
      out.push_back({"self_intersection", bodies[a]->name,
                     what + ": " + std::to_string(count[a][b]) + " crossing triangle pair(s); first: " +
                         first[a][b]});
    }
  return out;
}

double min_gap_mm(const TriMesh& a, const TriMesh& b, double search_mm, double plane_z_mm,
                  double ignore_near_plane_mm) {
  auto ignored_node = [&](const TriMesh& m, std::int32_t v) {
    return ignore_near_plane_mm > 0 &&
           ((m.region[v] & kAnchor) ||
            std::abs(m.position_mm[v].z() - plane_z_mm) < ignore_near_plane_mm);
  };
  auto one_way = [&](const TriMesh& from, const TriMesh& to) {
    std::vector<std::pair<std::int64_t, std::int32_t>> grid;
    auto idx = [&](double x) { return static_cast<std::int64_t>(std::floor(x / search_mm)); };
    for (std::size_t t = 0; t < to.triangle_count(); ++t) {
      bool skip = false;
      for (auto v : to.tri[t]) skip = skip || ignored_node(to, v);
      if (skip) continue;
      Vec3 tl = Vec3::Constant(1e300), th = Vec3::Constant(-1e300);
      for (auto v : to.tri[t]) {
        tl = tl.cwiseMin(to.position_mm[v]);
        th = th.cwiseMax(to.position_mm[v]);
      }
      for (auto i = idx(tl.x()); i <= idx(th.x()); ++i)
        for (auto j = idx(tl.y()); j <= idx(th.y()); ++j)
          for (auto k = idx(tl.z()); k <= idx(th.z()); ++k)
            grid.emplace_back(cell_key(i, j, k), static_cast<std::int32_t>(t));
    }
    std::sort(grid.begin(), grid.end());
    double best = search_mm;
    for (std::size_t v = 0; v < from.node_count(); ++v) {
      if (ignored_node(from, static_cast<std::int32_t>(v))) continue;
      const Vec3& p = from.position_mm[v];
      const auto ci = idx(p.x()), cj = idx(p.y()), ck = idx(p.z());
      for (int di = -1; di <= 1; ++di)
        for (int dj = -1; dj <= 1; ++dj)
          for (int dk = -1; dk <= 1; ++dk) {
            const auto key = cell_key(ci + di, cj + dj, ck + dk);
            auto it = std::lower_bound(grid.begin(), grid.end(), std::make_pair(key, std::int32_t{-1}));
            for (; it != grid.end() && it->first == key; ++it) {
              const auto& t = to.tri[it->second];
              const Vec3 q = closest_on_triangle(p, to.position_mm[t[0]], to.position_mm[t[1]],
                                                 to.position_mm[t[2]]);
              best = std::min(best, (q - p).norm());
            }
          }
    }
    return best;
  };
  return std::min(one_way(a, b), one_way(b, a));
}

QualityReport quality_report(const TriMesh& mesh) {
  QualityReport r;
  r.nodes = mesh.node_count();
  r.triangles = mesh.triangle_count();
  const EdgeTopology topo(mesh);
  r.edges = topo.edge_count();
  r.min_angle_deg = 180;
  double sum = 0, sum2 = 0, ar_sum = 0;
  r.edge_min_mm = 1e300;
  for (const auto& e : topo.edge) {
    const double l = (mesh.position_mm[e[0]] - mesh.position_mm[e[1]]).norm();
    r.edge_min_mm = std::min(r.edge_min_mm, l);
    r.edge_max_mm = std::max(r.edge_max_mm, l);
    sum += l;
    sum2 += l * l;
  }
  const double ne = std::max<double>(1, static_cast<double>(topo.edge_count()));
  r.edge_mean_mm = sum / ne;
  r.edge_std_mm = std::sqrt(std::max(0.0, sum2 / ne - r.edge_mean_mm * r.edge_mean_mm));
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    const auto& [a, b, c] = mesh.tri[t];
    const Vec3 &pa = mesh.position_mm[a], &pb = mesh.position_mm[b], &pc = mesh.position_mm[c];
    const double angles[3] = {triangle_angle_deg(pa, pb, pc), triangle_angle_deg(pb, pc, pa),
                              triangle_angle_deg(pc, pa, pb)};
    r.min_angle_deg = std::min({r.min_angle_deg, angles[0], angles[1], angles[2]});
    r.max_angle_deg = std::max({r.max_angle_deg, angles[0], angles[1], angles[2]});
    const double la = (pb - pc).norm(), lb = (pc - pa).norm(), lc = (pa - pb).norm();
    const double area = mesh.area_mm2(t);
    const double inradius = 2 * area / (la + lb + lc);
    const double ar = inradius > 0 ? std::max({la, lb, lc}) / (2 * std::sqrt(3.0) * inradius) : 1e300;
    r.max_aspect_ratio = std::max(r.max_aspect_ratio, ar);
    ar_sum += ar;
    r.area_mm2 += area;
  }
  r.mean_aspect_ratio = r.triangles ? ar_sum / static_cast<double>(r.triangles) : 0;
  if (topo.edge_count() == 0) r.edge_min_mm = 0;
  return r;
}

void throw_if_issues(const std::vector<QualityIssue>& issues, const std::string& context) {
  if (issues.empty()) return;
  std::string msg = context + ": " + std::to_string(issues.size()) + " problem(s):";
  for (const auto& i : issues) msg += "\n  [" + i.check + "] " + i.message;
  throw InputError(msg);
}

}  // namespace systole::geometry
