#include "solver/geometry/left_heart.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <sstream>
#include <stdexcept>

#include "solver/config/geometry_rules.h"
#include "solver/core/errors.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/meshing.h"
#include "solver/geometry/quality.h"
#include "solver/geometry/topology.h"

namespace systole::geometry {

namespace {

using detail::Ring;
using detail::Vec2;

// ---- (ours) construction constants, documented in docs/geometry.md -------------------------
constexpr double kRimMm = 2.5;            // plane between an orifice and the LV base ring
constexpr double kMinCurtainMm = 3.0;     // aorto-mitral curtain between the two orifices
constexpr double kLaAspect = 0.85;        // LA polar / equatorial semi-axis
constexpr double kSinusCommissureShare = 0.15;  // sinus bulge left at the commissures
constexpr double kRootHeightPerDiameter = 0.5;  // annulus -> sino-tubular junction
constexpr double kCuspHeightPerRadius = 0.5;    // closed cusp tip height / aortic radius
constexpr double kArchRadiusPerTubeRadius = 1.3;  // minimum arch bend radius
constexpr double kLayoutGapMm = 4.0;      // design gap used to place the descending aorta
constexpr double kPatchRadiusMm = 5.0;    // Bachmann and His stimulus patches
constexpr double kDescendingTaperPerDiameter = 2.0;
constexpr double kCrownInsetPerEdge = 0.15;  // cusp attachment inside the root's faces
constexpr double kMitralCoaptationPerLength = 0.35;  // closed mitral: coaptation strip / leaflet
constexpr double kPlaneBandMm = 3.0;      // clearance is not measured this close to the plane

void require(bool ok, const std::string& message) {
  if (!ok) throw InputError("invalid geometry: " + message);
}

std::string num(double v) {
  std::ostringstream s;
  s.precision(4);
  s << v;
  return s.str();
}

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

// Fraction of the circumscribing half-ellipsoid-cylinder volume pi a^2 L held by an ellipsoid
// truncated at u = -t (t in (-1, 0.5]): f(t) = (2/3 + t - t^3/3) / (1 + t), increasing.
double truncated_fraction(double t) { return (2.0 / 3.0 + t - t * t * t / 3.0) / (1.0 + t); }

double solve_increasing(const std::function<double(double)>& f, double target, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Dense samples of a meridian given as a function of a parameter: returns stations with equal
// arclength spacing (about `spacing`), at least `min_segments`.
std::vector<double> meridian_stations(const std::function<Vec2(double)>& curve, double p0, double p1,
                                      double spacing, int min_segments) {
  const int dense = 4000;
  std::vector<double> param(dense + 1), arc(dense + 1, 0.0);
  Vec2 prev = curve(p0);
  for (int i = 0; i <= dense; ++i) {
    param[i] = p0 + (p1 - p0) * i / dense;
    const Vec2 q = curve(param[i]);
    if (i) arc[i] = arc[i - 1] + (q - prev).norm();
    prev = q;
  }
  const int n = std::max(min_segments, static_cast<int>(std::lround(arc.back() / spacing)));
  return detail::equal_arclength_stations(param, arc, n);
}

int ring_count(double radius, double spacing, int min_count = 6) {
  return std::max(min_count, static_cast<int>(std::lround(2 * M_PI * radius / spacing)));
}

// Appends a ring of nodes centred at `centre` in the frame (e1, e2): node i at angle
// (2i + 1) pi / n, radius radius_of(angle).
Ring add_ring(TriMesh& mesh, int n, const Vec3& centre, const Vec3& e1, const Vec3& e2,
              const std::function<double(double)>& radius_of, std::uint32_t tags) {
  Ring ring;
  for (int i = 0; i < n; ++i) {
    const double th = (2 * i + 1) * M_PI / n;
    const double r = radius_of(th);
    ring.node.push_back(mesh.add_node(centre + r * (std::cos(th) * e1 + std::sin(th) * e2), tags));
    ring.angle.push_back(th);
  }
  return ring;
}

// Copies the nodes of `source` (positions only) into `mesh` as a ring with the same angles.
Ring copy_ring(TriMesh& mesh, const TriMesh& source, const Ring& ring, std::uint32_t tags) {
  Ring out;
  for (std::size_t i = 0; i < ring.node.size(); ++i) {
    out.node.push_back(mesh.add_node(source.position_mm[ring.node[i]], tags));
    out.angle.push_back(ring.angle[i]);
  }
  return out;
}

void add_triangles(TriMesh& mesh, const std::vector<Tri>& tris, Tissue tissue, double thickness) {
  for (const auto& t : tris) mesh.add_triangle(t[0], t[1], t[2], tissue, thickness);
}

// Tags every node within `radius` of the mesh node closest to `target`.
void tag_patch(TriMesh& mesh, const Vec3& target, double radius, std::uint32_t bit) {
  std::size_t best = 0;
  for (std::size_t i = 1; i < mesh.node_count(); ++i)
    if ((mesh.position_mm[i] - target).squaredNorm() < (mesh.position_mm[best] - target).squaredNorm())
      best = i;
  const Vec3 c = mesh.position_mm[best];
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if ((mesh.position_mm[i] - c).norm() <= radius) mesh.region[i] |= bit;
}

double distance_to_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  const Vec2 ab = b - a;
  const double w = std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
  return (p - (a + w * ab)).norm();
}

// A leaflet as a height field over a convex planar domain: boundary nodes are given in 3D
// (annulus nodes copied from the ring, free-edge nodes), interior points in 2D get
// z = height(x, y). Normals face -z (the "+" side, ours).
struct GraphBoundary {
  Vec3 position;
  std::uint32_t tags;
};
TriMesh graph_surface(std::string_view name, const std::vector<GraphBoundary>& boundary,
                      const std::vector<Vec2>& interior, const std::function<double(const Vec2&)>& height,
                      Tissue tissue, double thickness) {
  TriMesh mesh;
  mesh.name = std::string(name);
  mesh.kind = BodyKind::kLeaflet;
  std::vector<Vec2> pts;
  for (const auto& b : boundary) {
    mesh.add_node(b.position, b.tags);
    pts.emplace_back(b.position.x(), b.position.y());
  }
  for (const auto& p : interior) {
    mesh.add_node(Vec3(p.x(), p.y(), height(p)));
    pts.push_back(p);
  }
  for (const auto& t : detail::delaunay_2d(pts)) mesh.add_triangle(t[0], t[2], t[1], tissue, thickness);
  return mesh;
}

// ---- closed leaflets as "lenses" (ours) ---------------------------------------------------
// A closed leaflet between an anchored attachment W(s) and a free edge F(s), s in [-1, 1] from
// one commissure to the other, W(+-1) = F(+-1) (the commissures): the surface swept by the
// quadratic Bezier curves
//   B(s, t) = (1 - t)^2 W(s) + 2 t (1 - t) Q(s) + t^2 F(s),   t in [0, 1] from W to F,
// with a control point Q(s) set by the valve. Fibres along dB/ds: every fibre runs from one
// commissure to the other, and those near the attachment end on it. Meshed by Delaunay in a
// lens-shaped plane (arclength along the attachment, t times the length of the curve at s,
// capped by its concave envelope), then mapped: lengths in the plane are close to 3D lengths.
struct LensLeaflet {
  std::function<Vec3(double)> wall, free_edge, control;  // W(s), Q(s), F(s)
  double h_mesh;

  Vec3 point(double s, double t) const {
    return (1 - t) * (1 - t) * wall(s) + 2 * t * (1 - t) * control(s) + t * t * free_edge(s);
  }
  template <class F>
  static double length(const F& curve, double a, double b) {
    double len = 0;
    Vec3 prev = curve(a);
    for (int i = 1; i <= 400; ++i) {
      const Vec3 p = curve(a + (b - a) * i / 400);
      len += (p - prev).norm();
      prev = p;
    }
    return len;
  }
  // Values of s in [a, b] equally spaced in 3D along curve(s), ends included, >= min_segments.
  template <class F>
  std::vector<double> stations(const F& curve, double a, double b, int min_segments) const {
    const int dense = 2000;
    std::vector<double> param(dense + 1), arc(dense + 1, 0.0);
    for (int i = 0; i <= dense; ++i) {
      param[i] = a + (b - a) * i / dense;
      if (i) arc[i] = arc[i - 1] + (curve(param[i]) - curve(param[i - 1])).norm();
    }
    const int n = std::max(min_segments, static_cast<int>(std::ceil(arc.back() / h_mesh)));
    return detail::equal_arclength_stations(param, arc, n);
  }

  // Fibres along dB/ds at each triangle's centroid (s, t), in the triangle's plane.
  void set_fibres(TriMesh& mesh, const std::vector<Vec2>& uv) const {
    for (std::size_t tr = 0; tr < mesh.triangle_count(); ++tr) {
      const auto& v = mesh.tri[tr];
      const Vec2 c = (uv[v[0]] + uv[v[1]] + uv[v[2]]) / 3.0;
      const double e = 1e-3;
      const Vec3 along = point(std::min(1.0, c.x() + e), c.y()) - point(std::max(-1.0, c.x() - e), c.y());
      mesh.fibre[tr] = tangent_in_triangle(mesh, tr, along, Vec3::UnitX());
    }
  }

  // attachment: (s, position) of the attachment nodes from s = -1 to 1 (ends included), or
  // empty to sample W by equal arclength. Normals face `plus_side` at the belly (t = 0.3, s = 0).
  // rest: when given, a lens with the same attachment W whose surface is the leaflet's stress-free
  // shape: every node gets TriMesh::rest_position_mm = rest->point(s, t) at its own (s, t) (the
  // attachment's nodes stay where they are) and the triangles rest fibres from it (ours).
  TriMesh build(std::string_view name, Tissue tissue, double thickness, std::uint32_t attachment_tags,
                std::vector<std::pair<double, Vec3>> attachment, const Vec3& plus_side,
                const LensLeaflet* rest = nullptr) const {
    TriMesh mesh;
    mesh.name = std::string(name);
    mesh.kind = BodyKind::kLeaflet;
    // The lens plane: X = arclength along the attachment (centred), Y = t times the length of the
    // curve s -> B(s, .) capped above by its concave envelope over X (so the lens is convex and
    // Delaunay covers exactly it); X <-> s tabulated.
    const int n_tab = 400;
    std::vector<double> tab_s(n_tab + 1), tab_x(n_tab + 1, 0.0), tab_len(n_tab + 1);
    for (int i = 0; i <= n_tab; ++i) {
      tab_s[i] = -1 + 2.0 * i / n_tab;
      if (i) tab_x[i] = tab_x[i - 1] + (wall(tab_s[i]) - wall(tab_s[i - 1])).norm();
      tab_len[i] = (i == 0 || i == n_tab) ? 0.0 : length([&](double t) -> Vec3 { return point(tab_s[i], t); }, 0, 1);
    }
    const double Ls = 0.5 * tab_x.back();
    for (double& x : tab_x) x -= Ls;
    std::vector<int> hull;  // upper hull of (x, len): the concave envelope
    for (int i = 0; i <= n_tab; ++i) {
      while (hull.size() >= 2) {
        const int a = hull[hull.size() - 2], b = hull.back();
        const double cross = (tab_x[b] - tab_x[a]) * (tab_len[i] - tab_len[a]) - (tab_len[b] - tab_len[a]) * (tab_x[i] - tab_x[a]);
        if (cross >= 0) hull.pop_back();
        else break;
      }
      hull.push_back(i);
    }
    auto interp = [](const std::vector<double>& xs, const std::vector<double>& ys, double x) {
      const auto it = std::upper_bound(xs.begin(), xs.end(), x);
      const std::size_t k = std::clamp<std::size_t>(static_cast<std::size_t>(it - xs.begin()), 1, xs.size() - 1);
      const double w = (x - xs[k - 1]) / (xs[k] - xs[k - 1]);
      return ys[k - 1] + std::clamp(w, 0.0, 1.0) * (ys[k] - ys[k - 1]);
    };
    std::vector<double> hull_x, hull_len;
    for (int i : hull) hull_x.push_back(tab_x[i]), hull_len.push_back(tab_len[i]);
    auto top = [&](double x) { return interp(hull_x, hull_len, x); };
    auto x_of_s = [&](double s) { return interp(tab_s, tab_x, s); };
    auto s_of_x = [&](double x) { return interp(tab_x, tab_s, x); };
    std::vector<Vec2> uv;  // (s, t) of each node
    std::vector<Vec2> xy;  // its lens-plane position
    auto add = [&](double s, double t, const Vec3& p, std::uint32_t tags) {
      mesh.add_node(p, tags);
      uv.emplace_back(s, t);
      const double x = x_of_s(s);
      xy.emplace_back(x, t * top(x));
    };
    if (attachment.empty())
      for (double s : stations(wall, -1, 1, 6)) attachment.emplace_back(s, wall(s));
    for (const auto& [s, p] : attachment) add(s, 0, p, attachment_tags);
    // Free edge: each half equally spaced in 3D, the commissures excluded (attachment nodes).
    const auto left = stations(free_edge, -1, 0, 3), right = stations(free_edge, 0, 1, 3);
    for (std::size_t j = 1; j < left.size(); ++j) add(left[j], 1, free_edge(left[j]), kFreeEdge);
    for (std::size_t j = 1; j + 1 < right.size(); ++j) add(right[j], 1, free_edge(right[j]), kFreeEdge);
    const std::size_t n_boundary = xy.size();
    // Interior: a hexagonal lattice of the lens plane, kept 0.6 h away from its boundary.
    const double margin = 0.6 * h_mesh;
    const double height = *std::max_element(hull_len.begin(), hull_len.end());
    for (const Vec2& p : detail::hex_lattice(Vec2(-Ls, 0), Vec2(Ls, height), h_mesh)) {
      if (std::abs(p.x()) >= Ls) continue;
      const double y_top = top(p.x());
      if (p.y() < margin || p.y() > y_top - margin) continue;
      double d = 1e300;
      for (std::size_t i = 0; i < n_boundary; ++i) d = std::min(d, (p - xy[i]).norm());
      if (d < margin) continue;
      const double s = s_of_x(p.x()), t = p.y() / y_top;
      mesh.add_node(point(s, t), kRegionNone);
      uv.emplace_back(s, t);
      xy.push_back(p);
    }
    for (const auto& t : detail::delaunay_2d(xy)) mesh.add_triangle(t[0], t[1], t[2], tissue, thickness);
    {
      const Vec3 belly = point(0, 0.3);
      std::size_t best = 0;
      for (std::size_t tr = 1; tr < mesh.triangle_count(); ++tr)
        if ((mesh.centroid(tr) - belly).squaredNorm() < (mesh.centroid(best) - belly).squaredNorm()) best = tr;
      if (mesh.unit_normal(best).dot(plus_side) < 0) mesh.flip_orientation();
    }
    set_fibres(mesh, uv);
    if (rest) {
      TriMesh at_rest = mesh;
      for (std::size_t i = 0; i < mesh.node_count(); ++i)
        if (uv[i].y() > 0) at_rest.position_mm[i] = rest->point(uv[i].x(), uv[i].y());
      rest->set_fibres(at_rest, uv);
      mesh.rest_position_mm = std::move(at_rest.position_mm);
      mesh.rest_fibre = std::move(at_rest.fibre);
    }
    return mesh;
  }
};

// ---- the crown-shaped aortic valve (geometry.aortic_commissure_height_per_radius > 0), ours -----------
// Cusp k of the closed valve, centred on the azimuth phi_k = 120 k degrees about the root axis
// through A (up = -z), is a LensLeaflet:
// - W(s), the attachment, on the root wall at azimuth phi_k + s (60 deg - delta), height H s^2
//   (a U from the commissure tops at height H down to the nadir on the orifice ring), `inset`
//   inside the root's analytic wall;
// - F(s), the free edge, straight from the tip T (half_gap / sin 60 deg from the axis towards
//   phi_k, height h_tip) to the commissure top W(+-1); delta sets W(+-1) half_gap from the
//   commissure's radius so that neighbouring cusps stay 2 half_gap apart;
// - Q(s) = F(s) - h_tip (1 - |s|) up: the curves leave the wall towards the axis and end
//   vertically, so that near the free edges neighbouring cusps face each other across vertical
//   coaptation strips, pressed together by the aortic pressure.
// Every fibre runs from one commissure to the other and the fibres near the wall end on the
// anchored attachment, so the fibre-stiff tissue carries the load (measured with the closed valves
// alone, bench/structure/valve_load: the flat-annulus cusps' fibres end on free edges, and their
// cross-fibre law cannot).
struct CrownCusps {
  Vec3 centre;                 // the aortic orifice centre, in the valvular plane
  double H, h_tip, half_gap, h_mesh, thickness;
  double inset;  // the attachment's distance inside the root's analytic wall
  std::function<double(double, double)> wall_radius;  // (height above the plane, azimuth) -> mm

  Vec3 up() const { return -Vec3::UnitZ(); }
  // The attachment's commissure ends sit this far (in azimuth) inside the cusp's 120 degrees.
  double commissure_offset_rad() const {
    return std::asin(std::min(1.0, half_gap / (wall_radius(H, M_PI / 3) - inset)));
  }
  Vec3 wall_point(int k, double s) const {
    const double phi = 2 * M_PI * k / 3;
    const double th = phi + s * (M_PI / 3 - commissure_offset_rad()), z = H * s * s;
    return centre + (wall_radius(z, th) - inset) * Vec3(std::cos(th), std::sin(th), 0) + z * up();
  }
  Vec3 tip(int k) const {
    const double phi = 2 * M_PI * k / 3;
    return centre + half_gap / std::sin(M_PI / 3) * Vec3(std::cos(phi), std::sin(phi), 0) + h_tip * up();
  }
  LensLeaflet lens(int k) const {
    auto w = [this, k](double s) -> Vec3 { return wall_point(k, s); };
    auto f = [this, k](double s) -> Vec3 { return tip(k) + std::abs(s) * (wall_point(k, s < 0 ? -1.0 : 1.0) - tip(k)); };
    auto q = [this, f](double s) -> Vec3 { return f(s) - h_tip * (1 - std::abs(s)) * up(); };
    return LensLeaflet{w, f, q, h_mesh};
  }
  TriMesh build(int k, std::string_view name) const {
    return lens(k).build(name, Tissue::kAorticLeaflet, thickness, kAnchor | kAorticAnnulus, {}, up());
  }
};

}  // namespace

const TriMesh& LeftHeart::body(std::string_view name) const {
  for (const auto& b : bodies)
    if (b.name == name) return b;
  throw std::out_of_range("no body named '" + std::string(name) + "'");
}
TriMesh& LeftHeart::body(std::string_view name) {
  return const_cast<TriMesh&>(static_cast<const LeftHeart*>(this)->body(name));
}
std::vector<const TriMesh*> LeftHeart::body_pointers() const {
  std::vector<const TriMesh*> out;
  for (const auto& b : bodies) out.push_back(&b);
  return out;
}

LeftHeart build_left_heart(const config::Geometry& g, const config::Fluid& fluid) {
  // The cross-field rules first (parse_scenario has run them already for a parsed scenario;
  // a caller passing a hand-made Geometry gets the same messages).
  {
    std::vector<std::string> errors;
    config::check_geometry_rules(g, errors);
    if (!errors.empty()) {
      std::string msg = "invalid geometry:";
      for (const auto& e : errors) msg += "\n  " + e;
      throw InputError(msg);
    }
  }
  LeftHeart heart;
  HeartLayout& lay = heart.layout;
  const double h = g.target_edge_mm;
  const double h_ring = std::min(h, 0.8 * kRimMm);
  lay.ring_edge_mm = h_ring;

  // ---- LV: truncated prolate ellipsoid -----------------------------------------------------
  // Semi-axes a (equatorial, = lv_short_axis/2) and c (polar); the plane cuts the ellipsoid at
  // u = (z - z0)/c = -t, the apex is at depth L = c (1 + t). The cavity closed by the plane
  // holds pi a^2 L f(t); t solves f(t) = V / (pi a^2 L). t < 0: the equator lies above the
  // plane (the LV narrows from its base ring); t > 0: the LV bulges below its base ring.
  const double a = 0.5 * g.lv_short_axis_mm, L = g.lv_long_axis_mm;
  const double v_lv = g.lv_volume_ml * 1e3;
  const double q = v_lv / (M_PI * a * a * L);
  require(q <= 0.75, "geometry.lv_volume_ml = " + num(g.lv_volume_ml) +
                         " ml exceeds the largest cavity of a truncated prolate ellipsoid with "
                         "lv_short_axis_mm = " + num(g.lv_short_axis_mm) + " and lv_long_axis_mm = " +
                         num(L) + " (" + num(0.75 * M_PI * a * a * L * 1e-3) + " ml)");
  const double t = solve_increasing(truncated_fraction, q, -0.999, 0.5);
  const double c = L / (1 + t), z0 = t * c;
  lay.lv_truncation = t;
  lay.lv_polar_semi_axis_mm = c;
  const double base_radius = a * std::sqrt(1 - t * t);
  require(2 * base_radius >= g.mitral_diameter_mm + g.aortic_diameter_mm + 2 * kRimMm + kMinCurtainMm,
          "geometry.mitral_diameter_mm + aortic_diameter_mm = " +
              num(g.mitral_diameter_mm + g.aortic_diameter_mm) + " mm (plus 2 x " + num(kRimMm) +
              " mm rims and a " + num(kMinCurtainMm) + " mm curtain) do not fit in the LV base ring of "
              "diameter " + num(2 * base_radius) + " mm set by lv_short_axis_mm, lv_long_axis_mm and "
              "lv_volume_ml");

  TriMesh lv;
  lv.name = std::string(kLvBody);
  lv.kind = BodyKind::kChamber;
  const int n_base = ring_count(base_radius, h_ring, 12);
  {
    auto curve = [&](double beta) { return Vec2(z0 + c * std::sin(beta), a * std::cos(beta)); };
    const auto st = meridian_stations(curve, std::asin(-t), M_PI / 2, 0.866 * h, 4);
    const int nrings = static_cast<int>(st.size()) - 1;  // last station is the apex pole
    int apex_ring = 1, base_ring = 1;
    for (int k = 1; k < nrings; ++k) {
      const double depth = curve(st[k]).x();
      if (std::abs(depth - 0.85 * L) < std::abs(curve(st[apex_ring]).x() - 0.85 * L)) apex_ring = k;
      if (std::abs(depth - 0.15 * L) < std::abs(curve(st[base_ring]).x() - 0.15 * L)) base_ring = k;
    }
    std::vector<Tri> tris;
    Ring prev;
    for (int k = 0; k < nrings; ++k) {
      const Vec2 zr = curve(st[k]);
      const double r = k == 0 ? base_radius : zr.y();
      const int n = k == 0 ? n_base : ring_count(r, h);
      std::uint32_t tags = k == 0 ? kAnchor : kRegionNone;
      if (k == apex_ring) tags |= kLvApexRing;
      if (k == base_ring) tags |= kLvBaseRing;
      Ring ring = add_ring(lv, n, Vec3(0, 0, k == 0 ? 0.0 : zr.x()), Vec3::UnitX(), Vec3::UnitY(),
                           [r](double) { return r; }, tags);
      if (k) detail::stitch_rings(prev, ring, tris);
      prev = std::move(ring);
    }
    const auto apex = lv.add_node(Vec3(0, 0, L), kLvApex);
    detail::close_with_pole(prev, apex, tris);
    add_triangles(lv, tris, Tissue::kLvMyocardium, g.lv_wall_mm);
  }
  if (cavity_volume_ml(lv, 0) < 0) lv.flip_orientation();
  // Discrete volume correction (ours): scale x, y about the axis so that the polyhedron
  // closed by the plane holds exactly lv_volume_ml (a correction of order (h / a)^2).
  lay.lv_xy_scale = std::sqrt(g.lv_volume_ml / cavity_volume_ml(lv, 0));
  for (auto& p : lv.position_mm) p.head<2>() *= lay.lv_xy_scale;
  lay.lv_base_radius_mm = base_radius * lay.lv_xy_scale;
  double lv_max_radius = 0;
  for (const auto& p : lv.position_mm) lv_max_radius = std::max(lv_max_radius, p.head<2>().norm());
  // His bundle (ours): septum just below the aortic valve, azimuth of the aortic orifice (+x),
  // at 12 % of the long axis below the plane.
  {
    const double depth = 0.12 * L;
    const double u = (depth - z0) / c;
    tag_patch(lv, Vec3(a * std::sqrt(1 - u * u) * lay.lv_xy_scale, 0, depth), kPatchRadiusMm, kHisBundle);
  }
  // LV fibres: helix at lv_fibre_angle_deg, counter-clockwise seen from the apex (about +z),
  // rising from apex to base: f = cos(alpha) e_circ + sin(alpha) e_apex->base.
  {
    const double alpha = g.lv_fibre_angle_deg * M_PI / 180;
    for (std::size_t tr = 0; tr < lv.triangle_count(); ++tr) {
      const Vec3 cen = lv.centroid(tr), n = lv.unit_normal(tr);
      const Vec3 radial(cen.x(), cen.y(), 0);
      const Vec3 circ = tangent_in_triangle(lv, tr, Vec3::UnitZ().cross(radial), Vec3::UnitY());
      Vec3 up = n.cross(circ);  // inward normal x circumferential = towards the base
      if (up.z() > 0) up = -up;
      lv.fibre[tr] = (std::cos(alpha) * circ + std::sin(alpha) * up).normalized();
    }
  }

  // ---- valvular plane ----------------------------------------------------------------------
  const double r_m = 0.5 * g.mitral_diameter_mm, r_a = 0.5 * g.aortic_diameter_mm;
  const double r_in = lay.lv_base_radius_mm * std::cos(M_PI / n_base);
  const double x_m = -r_in + kRimMm + r_m, x_a = r_in - kRimMm - r_a;
  const Vec3 M(x_m, 0, 0), A(x_a, 0, 0);
  const int n_m = 4 * std::max(4, static_cast<int>(std::lround(2 * M_PI * r_m / h_ring / 4)));
  const int n_a = 6 * std::max(2, static_cast<int>(std::lround(2 * M_PI * r_a / h_ring / 6)));
  TriMesh plane;
  plane.name = std::string(kValvularPlaneBody);
  plane.kind = BodyKind::kRigid;
  Ring mitral_ring, aortic_ring;
  {
    std::vector<Vec2> pts;
    std::vector<int> group;
    for (int i = 0; i < n_base; ++i) {
      const Vec3& p = lv.position_mm[i];  // LV ring 0 = nodes 0 .. n_base-1
      plane.add_node(p, kRegionNone);
      pts.emplace_back(p.x(), p.y());
      group.push_back(0);
    }
    mitral_ring = add_ring(plane, n_m, M, Vec3::UnitX(), Vec3::UnitY(), [&](double) { return r_m; },
                           kMitralAnnulus);
    aortic_ring = add_ring(plane, n_a, A, Vec3::UnitX(), Vec3::UnitY(), [&](double) { return r_a; },
                           kAorticAnnulus);
    for (std::size_t i = n_base; i < plane.node_count(); ++i) {
      pts.emplace_back(plane.position_mm[i].x(), plane.position_mm[i].y());
      group.push_back(i < static_cast<std::size_t>(n_base + n_m) ? 1 : 2);
    }
    const double margin = 0.6 * h_ring;
    for (const Vec2& p : detail::hex_lattice(Vec2(-r_in, -r_in), Vec2(r_in, r_in), h_ring)) {
      if (p.norm() > r_in - margin) continue;
      if ((p - M.head<2>()).norm() < r_m + margin || (p - A.head<2>()).norm() < r_a + margin) continue;
      plane.add_node(Vec3(p.x(), p.y(), 0));
      pts.push_back(p);
      group.push_back(3);
    }
    for (const auto& tr : detail::delaunay_2d(pts)) {
      const int g0 = group[tr[0]];
      if ((g0 == 1 || g0 == 2) && group[tr[1]] == g0 && group[tr[2]] == g0) continue;  // a hole
      plane.add_triangle(tr[0], tr[1], tr[2], Tissue::kValvularPlane, g.lv_wall_mm, Vec3::UnitX());
    }
    const EdgeTopology topo(plane);
    std::size_t boundary = 0;
    for (std::size_t e = 0; e < topo.edge_count(); ++e) boundary += topo.face_count_of(e) == 1;
    if (boundary != static_cast<std::size_t>(n_base + n_m + n_a))
      throw std::logic_error("valvular plane: orifice rings not recovered by the triangulation");
  }
  heart.plane = {0, Vec3::Zero(), lay.lv_base_radius_mm, M, r_m, A, r_a};

  // ---- LA: sheared truncated spheroid on the mitral ring -----------------------------------
  // Slices at height y above the plane are circles of radius r(y) (a spheroid of equatorial
  // radius R and polar semi-axis c_la = 0.85 R cut so that r(0) = r_m), centred at
  // x_m - S(y): S(y) = r(y) - r_m up to the equator (the anterior wall stays vertical above the
  // anterior annulus, away from the aortic root), constant above (ours). Shearing slices keeps
  // the volume: V = pi R^2 c (2/3 + tau - tau^3/3), tau = sqrt(1 - r_m^2 / R^2).
  const double v_la = g.la_volume_ml * 1e3;
  auto la_volume = [&](double R) {
    const double cc = kLaAspect * R, tau = std::sqrt(std::max(0.0, 1 - r_m * r_m / (R * R)));
    return M_PI * R * R * cc * (2.0 / 3.0 + tau - tau * tau * tau / 3.0);
  };
  require(v_la > la_volume(r_m * 1.0001),
          "geometry.la_volume_ml = " + num(g.la_volume_ml) + " ml is too small for an atrium on a mitral "
          "orifice of mitral_diameter_mm = " + num(g.mitral_diameter_mm) + " (minimum " +
              num(la_volume(r_m) * 1e-3) + " ml)");
  const double R_la = solve_increasing(la_volume, v_la, r_m * 1.0001, 500);
  const double c_la = kLaAspect * R_la;
  const double tau = std::sqrt(1 - r_m * r_m / (R_la * R_la));
  const double y_c = tau * c_la;
  lay.la_equatorial_radius_mm = R_la;
  lay.la_polar_semi_axis_mm = c_la;
  auto la_r = [&](double y) {
    const double u = std::clamp((y - y_c) / c_la, -1.0, 1.0);
    return R_la * std::sqrt(1 - u * u);
  };
  auto la_shift = [&](double y) { return y <= y_c ? la_r(y) - r_m : R_la - r_m; };
  TriMesh la;
  la.name = std::string(kLaBody);
  la.kind = BodyKind::kChamber;
  {
    auto curve = [&](double beta) { return Vec2(y_c + c_la * std::sin(beta), R_la * std::cos(beta)); };
    // Rings are spaced along the posterior meridian, the longest one of the sheared stack.
    auto posterior = [&](double beta) {
      const double y = y_c + c_la * std::sin(beta);
      return Vec2(y, la_shift(y) + R_la * std::cos(beta));
    };
    const auto st = meridian_stations(posterior, std::asin(-tau), M_PI / 2, 0.866 * h, 4);
    const int nrings = static_cast<int>(st.size()) - 1;
    std::vector<Tri> tris;
    Ring prev = copy_ring(la, plane, mitral_ring, kAnchor | kMitralAnnulus);
    for (int k = 1; k < nrings; ++k) {
      const Vec2 yr = curve(st[k]);
      const double y = yr.x(), r = yr.y();
      Ring ring = add_ring(la, ring_count(r, h), Vec3(x_m - la_shift(y), 0, -y), Vec3::UnitX(),
                           Vec3::UnitY(), [r](double) { return r; }, kRegionNone);
      detail::stitch_rings(prev, ring, tris);
      prev = std::move(ring);
    }
    const double y_top = y_c + c_la;
    const auto pole = la.add_node(Vec3(x_m - la_shift(y_top), 0, -y_top));
    detail::close_with_pole(prev, pole, tris);
    add_triangles(la, tris, Tissue::kLaMyocardium, g.la_wall_mm);
    lay.la_height_mm = y_top;
  }
  if (cavity_volume_ml(la, 0) < 0) la.flip_orientation();
  // Discrete volume correction (ours): scale heights (the mitral ring stays in the plane).
  lay.la_height_scale = g.la_volume_ml / cavity_volume_ml(la, 0);
  for (auto& p : la.position_mm) p.z() *= lay.la_height_scale;
  lay.la_height_mm *= lay.la_height_scale;
  auto la_point = [&](double y, double th) {
    const double r = la_r(y);
    return Vec3(x_m - la_shift(y) + r * std::cos(th), r * std::sin(th), -y * lay.la_height_scale);
  };
  // LA fibres (ours: along the vertical axis = the meridians of the slice stack), pointing up.
  for (std::size_t tr = 0; tr < la.triangle_count(); ++tr) {
    const Vec3 cen = la.centroid(tr);
    const double y = -cen.z() / lay.la_height_scale;
    const double u = std::clamp((y - y_c) / c_la, -1.0, 1.0), s = std::sqrt(1 - u * u);
    const double th = std::atan2(cen.y(), cen.x() - (x_m - la_shift(y)));
    const double dr = -R_la * u / c_la;                    // r'(y) * sqrt(1 - u^2)
    const double ds = y <= y_c ? dr : 0.0;                 // S'(y) * sqrt(1 - u^2)
    const Vec3 meridian(-ds + dr * std::cos(th), dr * std::sin(th), -lay.la_height_scale * s);
    Vec3 f = tangent_in_triangle(la, tr, meridian, -Vec3::UnitZ());
    la.fibre[tr] = f;
  }
  // Pulmonary-vein ostia (ours): 40 degrees either side of the posterior direction (-x), at
  // the equator +- 0.35 c_la; left veins on +y. Cap triangles become vein_ostium tissue.
  {
    const double r_pv = 0.5 * g.pulmonary_vein_diameter_mm;
    const std::pair<Region, Vec3> ostia[4] = {
        {kPvOstiumLeftSuperior, la_point(y_c + 0.35 * c_la, M_PI - 0.7)},
        {kPvOstiumLeftInferior, la_point(y_c - 0.35 * c_la, M_PI - 0.7)},
        {kPvOstiumRightSuperior, la_point(y_c + 0.35 * c_la, M_PI + 0.7)},
        {kPvOstiumRightInferior, la_point(y_c - 0.35 * c_la, M_PI + 0.7)}};
    for (const auto& [bit, centre] : ostia)
      for (std::size_t tr = 0; tr < la.triangle_count(); ++tr)
        if ((la.centroid(tr) - centre).norm() <= r_pv) {
          la.tissue[tr] = Tissue::kVeinOstium;
          for (auto v : la.tri[tr]) la.region[v] |= bit;
        }
  }
  // Bachmann bundle (ours): anterior LA roof, at 75 % of the LA height on the anterior wall.
  tag_patch(la, la_point(0.75 * (y_c + c_la), 0.0), kPatchRadiusMm, kBachmannBundle);

  // ---- mitral leaflets (closed) -----------------------------------------------------------
  // Each leaflet is a LensLeaflet (ours) over its half of the orifice: the attachment W(s) is
  // the annulus arc (the ring's nodes, in the plane), the free edge F(s) a coaptation line
  // parallel to y at x = x_m +- g/2 (g = valve_gap_mm; 0: one ring edge, the free edges ending
  // on the ring's nodes at the commissures; else on the circle), s = y / y_end. The curves from
  // W(s) head for Q(s), depth z_q (1 - s^2) under the coaptation line, and end vertically at F(s),
  // l_c = 0.35 l (1 - s^2) deeper: the leaflets meet across vertical coaptation strips that the
  // LV's pressure presses together, and z_q is solved so that the middle curve is
  // mitral_leaflet_length_mm = l long. Fibres from commissure to commissure (along y).
  const double x_ring = r_m * std::sin(M_PI / n_m);
  require(g.valve_gap_mm < 2 * x_ring,
          "geometry.valve_gap_mm = " + num(g.valve_gap_mm) + " must be shorter than the mitral ring edge (" +
              num(2 * x_ring) + " mm at target_edge_mm = " + num(g.target_edge_mm) + "); 0 gives one ring edge");
  const bool ring_gap = g.valve_gap_mm == 0;  // the free edges end on the ring's nodes
  const double x_f = ring_gap ? x_ring : 0.5 * g.valve_gap_mm;
  const double y_end = std::sqrt(r_m * r_m - x_f * x_f);
  const double l_leaf = g.mitral_leaflet_length_mm, l_c = kMitralCoaptationPerLength * l_leaf;
  // open: the rest shape's opening (geometry.mitral_rest_opening_mm, ours): the free edge and the
  // control points moved towards the leaflet's own annulus by open/2 (1 - s^2).
  auto mitral_lens = [&](double sgn, double z_q, double open = 0) {
    auto w = [=](double s) -> Vec3 {
      const double y = s * y_end;
      return M + Vec3(sgn * std::sqrt(std::max(0.0, r_m * r_m - y * y)), y, 0);
    };
    auto f = [=](double s) -> Vec3 {
      return M + Vec3(sgn * (x_f + 0.5 * open * (1 - s * s)), s * y_end, (z_q + l_c) * (1 - s * s));
    };
    auto q = [=](double s) -> Vec3 {
      return M + Vec3(sgn * (x_f + 0.5 * open * (1 - s * s)), s * y_end, z_q * (1 - s * s));
    };
    return LensLeaflet{w, f, q, h_ring};
  };
  auto middle_length = [&](double z_q, double open = 0) {
    const LensLeaflet lens = mitral_lens(1, z_q, open);
    return LensLeaflet::length([&](double t) -> Vec3 { return lens.point(0, t); }, 0, 1);
  };
  require(middle_length(0) < l_leaf,
          "geometry.mitral_leaflet_length_mm = " + num(l_leaf) + " is too short to close the mitral orifice: it must "
          "exceed " + num(middle_length(0)) + " mm (the span from the annulus to the coaptation line, mitral_diameter_mm / 2 = " +
              num(r_m) + " mm, plus the coaptation strip)");
  const double z_q = solve_increasing(middle_length, l_leaf, 0, 4 * l_leaf);
  const double z_c = z_q + l_c;
  lay.mitral_coaptation_depth_mm = z_c;
  // The rest shape (geometry.mitral_rest_opening_mm > 0, ours): the same leaflets opened, the
  // middle curve kept l long (its control depth re-solved).
  const double open = g.mitral_rest_opening_mm;
  require(open >= 0 && x_f + 0.5 * open <= 0.75 * r_m,
          "geometry.mitral_rest_opening_mm = " + num(open) + " must be in [0, " + num(2 * (0.75 * r_m - x_f)) +
              "] mm: each rest free edge's middle must stay within 3/4 of the mitral radius (mitral_diameter_mm / 2 = " +
              num(r_m) + " mm) from the orifice's centre");
  const double z_q_rest =
      open > 0 ? solve_increasing([&](double z) { return middle_length(z, open); }, l_leaf, 0, 4 * l_leaf) : z_q;
  lay.mitral_rest_depth_mm = open > 0 ? z_q_rest + l_c : 0;
  lay.leaflet_gap_mm = 2 * x_f;
  for (int side = 0; side < 2; ++side) {
    const double sgn = side == 0 ? 1.0 : -1.0;  // anterior (+x, towards the aortic valve) / posterior
    // the attachment: the ring's nodes on this side (bitwise), the free edge's ends on the circle
    std::vector<std::pair<double, Vec3>> attachment;
    for (std::size_t i = 0; i < mitral_ring.node.size(); ++i) {
      const Vec3& p = plane.position_mm[mitral_ring.node[i]];
      if (sgn * (p.x() - M.x()) >= x_f - 1e-9 * r_m) attachment.emplace_back((p.y() - M.y()) / y_end, p);
    }
    std::sort(attachment.begin(), attachment.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    if (ring_gap) {  // the commissures are ring nodes: s = +-1 exactly
      attachment.front().first = -1;
      attachment.back().first = 1;
    } else {
      attachment.insert(attachment.begin(), {-1.0, M + Vec3(sgn * x_f, -y_end, 0)});
      attachment.emplace_back(1.0, M + Vec3(sgn * x_f, y_end, 0));
    }
    const LensLeaflet rest = mitral_lens(sgn, z_q_rest, open);
    heart.bodies.push_back(mitral_lens(sgn, z_q).build(side == 0 ? kMitralAnteriorBody : kMitralPosteriorBody,
                                                        Tissue::kMitralLeaflet, g.mitral_leaflet_thickness_mm,
                                                        kAnchor | kMitralAnnulus, attachment, -Vec3::UnitZ(),
                                                        open > 0 ? &rest : nullptr));
  }
  // Leaflets must stay inside the LV cavity (checked again on the mesh below).
  {
    const double depth_limit = L - 2 * kMinBodyGapMm;
    require(z_c < depth_limit, "geometry.mitral_leaflet_length_mm = " + num(g.mitral_leaflet_length_mm) +
                                   " reaches " + num(z_c) + " mm below the valvular plane, longer than the LV "
                                   "(lv_long_axis_mm = " + num(L) + ")");
    require(lay.mitral_rest_depth_mm < depth_limit,
            "geometry.mitral_rest_opening_mm = " + num(open) + " with mitral_leaflet_length_mm = " +
                num(g.mitral_leaflet_length_mm) + " puts the leaflets' rest free edge " + num(lay.mitral_rest_depth_mm) +
                " mm below the valvular plane, deeper than the LV allows (lv_long_axis_mm = " + num(L) + " less " +
                num(2 * kMinBodyGapMm) + " mm); reduce the opening");
  }

  // ---- aortic cusps (closed) ----------------------------------------------------------------
  // Cusp k spans the sector around phi_k = 120 k degrees between commissures at phi_k +- 60
  // (a commissure faces the LA, -x). Its free edges run parallel to the commissure radii, g/2
  // from them (g = valve_gap_mm, ending on the ring's chord across the commissure; 0: one ring
  // edge, ending on the ring's nodes), and meet at
  // a tip near the centre, raised to the coaptation height h_c = 0.5 r_a; the belly is a height
  // field between the annulus and the free edges (ours). Under the aortic pressure this valve
  // does not hold (measured with the closed valves alone): with the commissures in the flat
  // annulus, nothing carries the free edges but their contact.
  const double h_c = kCuspHeightPerRadius * r_a;
  lay.cusp_coaptation_height_mm = h_c;
  const bool crown = g.aortic_commissure_height_per_radius > 0;  // the curtain cusps, built with the root below
  if (!crown) {
    const double half_ring_edge = r_a * std::sin(M_PI / n_a);
    require(g.valve_gap_mm < 2 * half_ring_edge,
            "geometry.valve_gap_mm = " + num(g.valve_gap_mm) + " must be shorter than the aortic ring edge (" +
                num(2 * half_ring_edge) + " mm at target_edge_mm = " + num(g.target_edge_mm) + "); 0 gives one ring edge");
    const bool ring_gap = g.valve_gap_mm == 0;  // the free edges end on the ring's nodes
    const double half_gap = ring_gap ? half_ring_edge : 0.5 * g.valve_gap_mm;
    const double d_tip = half_gap / std::sin(M_PI / 3);
    const double h_cusp = h_ring * 0.8;
    for (int k = 0; k < 3; ++k) {
      const double phi = 2 * M_PI * k / 3;
      const Vec2 dir(std::cos(phi), std::sin(phi));
      const Vec2 tip = A.head<2>() + d_tip * dir;
      std::vector<GraphBoundary> boundary;
      Vec2 e1 = Vec2::Zero(), e2 = Vec2::Zero();
      for (std::size_t i = 0; i < aortic_ring.node.size(); ++i) {
        const double rel = std::remainder(aortic_ring.angle[i] - phi, 2 * M_PI);
        if (std::abs(rel) >= M_PI / 3) continue;
        const Vec3& p = plane.position_mm[aortic_ring.node[i]];
        boundary.push_back({p, kAnchor | kAorticAnnulus});
        if (std::abs(rel + M_PI / 3 - M_PI / n_a) < 1e-9) e1 = p.head<2>();
        if (std::abs(rel - M_PI / 3 + M_PI / n_a) < 1e-9) e2 = p.head<2>();
      }
      // The free edges' ends c1, c2: on the chord across each commissure, half_gap from it.
      auto chord_end = [&](const Vec2& e, double commissure) {
        const Vec2 mid = A.head<2>() + r_a * std::cos(M_PI / n_a) * Vec2(std::cos(commissure), std::sin(commissure));
        return Vec2(mid + (e - mid) * (half_gap / half_ring_edge));
      };
      const Vec2 c1 = ring_gap ? e1 : chord_end(e1, phi - M_PI / 3), c2 = ring_gap ? e2 : chord_end(e2, phi + M_PI / 3);
      if (!ring_gap)
        for (const Vec2& c : {c1, c2}) boundary.push_back({Vec3(c.x(), c.y(), 0), kAnchor | kAorticAnnulus});
      const double rho_tip = d_tip / r_a;
      auto free_height = [&](const Vec2& p) {
        return h_c * std::max(0.0, 1 - (p - A.head<2>()).norm() / r_a) / (1 - rho_tip);
      };
      const Vec2 inside = A.head<2>() + 0.5 * r_a * dir;
      for (const auto& [from, to] : {std::pair{c1, tip}, std::pair{tip, c2}}) {
        const double len = (to - from).norm();
        Vec2 out(-(to - from).y(), (to - from).x());
        out.normalize();
        if (out.dot(inside - from) > 0) out = -out;
        const int nseg = std::max(2, static_cast<int>(std::ceil(len / h_cusp)));
        for (int j = 1; j <= nseg; ++j) {
          if (j == nseg && to != tip) break;  // the end node is an annulus node
          const double s = static_cast<double>(j) / nseg;
          const Vec2 p = from + s * (to - from) + 4e-4 * len * s * (1 - s) * out;
          boundary.push_back({Vec3(p.x(), p.y(), -free_height(p)), kFreeEdge});
        }
      }
      auto d_free = [&](const Vec2& p) {
        return std::min(distance_to_segment(p, c1, tip), distance_to_segment(p, tip, c2));
      };
      auto side_ok = [&](const Vec2& p, const Vec2& from, const Vec2& to, double margin) {
        Vec2 nrm(-(to - from).y(), (to - from).x());
        nrm.normalize();
        if (nrm.dot(inside - from) < 0) nrm = -nrm;
        return nrm.dot(p - from) >= margin;
      };
      std::vector<Vec2> interior;
      const double margin = 0.6 * h_cusp;
      for (const Vec2& p : detail::hex_lattice(A.head<2>() - Vec2(r_a, r_a), A.head<2>() + Vec2(r_a, r_a), h_cusp)) {
        if ((p - A.head<2>()).norm() > r_a - margin) continue;
        if (!side_ok(p, c1, tip, margin) || !side_ok(p, tip, c2, margin)) continue;
        interior.push_back(p);
      }
      auto height = [&](const Vec2& p) {
        const double d_arc = std::max(0.0, r_a - (p - A.head<2>()).norm()), df = d_free(p);
        return -d_arc / (d_arc + df + 1e-300) * free_height(p);
      };
      TriMesh cusp = graph_surface(kAorticCuspBodies[k], boundary, interior, height, Tissue::kAorticLeaflet,
                                   g.aortic_leaflet_thickness_mm);
      for (std::size_t tr = 0; tr < cusp.triangle_count(); ++tr) {
        const Vec3 rel = cusp.centroid(tr) - A;
        cusp.fibre[tr] = tangent_in_triangle(cusp, tr, Vec3::UnitZ().cross(Vec3(rel.x(), rel.y(), 0)),
                                             Vec3::UnitX());
      }
      heart.bodies.push_back(std::move(cusp));
    }
  }

  // ---- aorta: root with three sinuses, 180-degree arch, descending aorta ---------------------
  const double R_root = 0.5 * g.aortic_root_diameter_mm, r_arch = 0.5 * g.aortic_arch_diameter_mm;
  const double r_desc = 0.5 * g.aortic_descending_diameter_mm;
  require(R_root > r_arch, "geometry.aortic_root_diameter_mm = " + num(g.aortic_root_diameter_mm) +
                               " must exceed aortic_arch_diameter_mm = " + num(g.aortic_arch_diameter_mm) +
                               " (the sinuses of Valsalva bulge beyond the ascending aorta)");
  const double y_stj = kRootHeightPerDiameter * g.aortic_root_diameter_mm;
  lay.root_height_mm = y_stj;
  auto root_base = [&](double s) { return r_a + (r_arch - r_a) * smoothstep(s / y_stj); };
  auto sinus_peak = [&](double amp) {
    double m = 0;
    for (int i = 0; i <= 400; ++i) {
      const double s = y_stj * i / 400;
      m = std::max(m, root_base(s) + amp * std::sin(M_PI * s / y_stj));
    }
    return m;
  };
  const double amp = solve_increasing(sinus_peak, R_root, 0, 2 * R_root);
  lay.sinus_amplitude_mm = amp;
  auto lobe = [](double th) {
    return kSinusCommissureShare + (1 - kSinusCommissureShare) * 0.5 * (1 + std::cos(3 * th));
  };
  // Root vs LA: the LA's anterior wall is the vertical plane x = x_m + r_m below its equator.
  {
    double root_min_x = 1e300;
    for (int i = 0; i <= 60; ++i)
      for (int j = 0; j <= 72; ++j) {
        const double s = y_stj * i / 60, th = 2 * M_PI * j / 72;
        const double r = root_base(s) + lobe(th) * amp * std::sin(M_PI * s / y_stj);
        root_min_x = std::min(root_min_x, x_a + r * std::cos(th));
      }
    require(root_min_x - (x_m + r_m) >= kMinBodyGapMm,
            "geometry.aortic_root_diameter_mm = " + num(g.aortic_root_diameter_mm) +
                " makes the aortic root reach the left atrium (gap " + num(root_min_x - (x_m + r_m)) +
                " mm < " + num(kMinBodyGapMm) + " mm); reduce it or aortic_diameter_mm / mitral_diameter_mm, "
                "or enlarge lv_short_axis_mm");
  }
  // Descending aorta placement (ours): beside the heart on +y, in the vertical plane x = x_a.
  const double y_d = std::max({std::sqrt(std::max(0.0, std::pow(lv_max_radius + r_arch + kLayoutGapMm, 2) - x_a * x_a)),
                               R_root + r_arch + kLayoutGapMm, R_la + r_arch + kLayoutGapMm,
                               2 * kArchRadiusPerTubeRadius * r_arch});
  const double R_arch = 0.5 * y_d;
  lay.arch_radius_mm = R_arch;
  lay.descending_offset_mm = y_d;
  const Vec3 up = -Vec3::UnitZ(), side = Vec3::UnitY();
  const double s_arch0 = y_stj, s_arch1 = y_stj + M_PI * R_arch;
  const double s_end = s_arch1 + y_stj + L;  // the descending aorta ends level with the apex
  auto centre = [&](double s) -> Vec3 {
    if (s <= s_arch0) return A + s * up;
    if (s <= s_arch1) {
      const double ph = (s - s_arch0) / R_arch;
      return A + y_stj * up + R_arch * (1 - std::cos(ph)) * side + R_arch * std::sin(ph) * up;
    }
    return A + y_stj * up + 2 * R_arch * side - (s - s_arch1) * up;
  };
  auto tangent = [&](double s) -> Vec3 {
    if (s <= s_arch0) return up;
    if (s <= s_arch1) {
      const double ph = (s - s_arch0) / R_arch;
      return (std::sin(ph) * side + std::cos(ph) * up).normalized();
    }
    return -up;
  };
  auto mean_radius = [&](double s) {
    if (s <= s_arch0) return root_base(s) + (kSinusCommissureShare + 0.5 * (1 - kSinusCommissureShare)) * amp *
                                                std::sin(M_PI * s / y_stj);
    if (s <= s_arch1) return r_arch;
    return r_arch + (r_desc - r_arch) * smoothstep((s - s_arch1) / (kDescendingTaperPerDiameter * 2 * r_desc));
  };
  auto radius = [&](double s, double th) {
    if (s <= s_arch0) return root_base(s) + lobe(th) * amp * std::sin(M_PI * s / y_stj);
    return mean_radius(s);
  };
  // The crown: the root wall is held (anchored, ours) up to one ring spacing above the cusps'
  // attachment, so that the attachment stays sealed against it; 0 without the crown.
  std::function<double(double)> crown_hold_height = [](double) { return 0.0; };
  const double crown_H = g.aortic_commissure_height_per_radius * r_a;
  lay.aortic_commissure_height_mm = crown ? crown_H : 0.0;
  lay.aortic_crown_height_mm = crown ? crown_H + 0.866 * h : 0.0;
  if (crown) {
    const double H = crown_H;
    require(g.aortic_commissure_height_per_radius >= kCuspHeightPerRadius + 0.1 && H < 0.8 * y_stj,
            "geometry.aortic_commissure_height_per_radius = " + num(g.aortic_commissure_height_per_radius) +
                " must be at least " + num(kCuspHeightPerRadius + 0.1) + " (the closed cusps' tips are at " +
                num(kCuspHeightPerRadius) + " radii) and put the commissures (" + num(H) +
                " mm) below 0.8 x the root height (" + num(0.8 * y_stj) + " mm); 0 gives the flat-annulus cusps");
    const double half_ring_edge = r_a * std::sin(M_PI / n_a);
    const double half_gap = g.valve_gap_mm == 0 ? half_ring_edge : 0.5 * g.valve_gap_mm;
    CrownCusps crown_cusps{A, H, h_c, half_gap, 0.8 * h_ring,
                           g.aortic_leaflet_thickness_mm, kCrownInsetPerEdge * h,
                           [&](double z_up, double th) { return radius(std::clamp(z_up, 0.0, s_arch0), th); }};
    for (int k = 0; k < 3; ++k) heart.bodies.push_back(crown_cusps.build(k, kAorticCuspBodies[k]));
    const double sweep = M_PI / 3 - crown_cusps.commissure_offset_rad();
    crown_hold_height = [H, sweep, margin = 0.866 * h](double th) {
      const double rel = std::abs(std::remainder(th, 2 * M_PI / 3));  // from the nearest cusp centre
      return H * std::min(1.0, std::pow(rel / sweep, 2)) + margin;
    };
  }

  TriMesh aorta;
  aorta.name = std::string(kAortaBody);
  aorta.kind = BodyKind::kVessel;
  // The Darcy outflow region: the descending aorta's last darcy_region_length_per_diameter
  // diameters, where the tube has its own radius: below the taper from the arch's radius
  // (kDescendingTaperPerDiameter diameters) and one radius more (the scenes' probe of the
  // descending aorta sits one radius above the region).
  {
    const double d_desc = 2 * r_desc, straight_mm = s_end - s_arch1;
    const double longest = (straight_mm - kDescendingTaperPerDiameter * d_desc - r_desc) / d_desc;
    require(g.darcy_region_length_per_diameter <= longest,
            "geometry.darcy_region_length_per_diameter = " + num(g.darcy_region_length_per_diameter) + " (" +
                num(g.darcy_region_length_per_diameter * d_desc) +
                " mm) puts the Darcy region outside the descending aorta's straight tube: below the arch it is " +
                num(straight_mm) + " mm long, its first " + num(kDescendingTaperPerDiameter * d_desc) +
                " mm taper from the arch's diameter, so at most " + num(longest) + " descending diameters (" +
                num(longest * d_desc) + " mm) fit (aortic_descending_diameter_mm = " +
                num(g.aortic_descending_diameter_mm) + ")");
  }
  const double s_outflow = s_end - g.darcy_region_length_per_diameter * 2 * r_desc;
  {
    // Rotation-minimising frame by parallel transport on a fine centreline sampling.
    const int dense = std::max(400, static_cast<int>(s_end / 0.1));
    std::vector<Vec3> e1s(dense + 1);
    Vec3 e1 = Vec3::UnitX();
    for (int i = 0; i <= dense; ++i) {
      const Vec3 tt = tangent(s_end * i / dense);
      e1 = (e1 - e1.dot(tt) * tt).normalized();
      e1s[i] = e1;
    }
    auto frame = [&](double s, Vec3& f1, Vec3& f2) {
      const Vec3 tt = tangent(s);
      const int i = std::clamp(static_cast<int>(std::lround(s / s_end * dense)), 0, dense);
      f1 = (e1s[i] - e1s[i].dot(tt) * tt).normalized();
      f2 = f1.cross(tt);  // (x, y) at the root, where the tangent is -z
    };
    auto curve = [&](double s) { return Vec2(s, mean_radius(s)); };
    // Rings at 0.866 h along the meridian before and after the arch, one at each end of it. The
    // arch itself is meshed by longitudinal lines (ours): rings there would all pass through the
    // bend's axis, so the wall between two of them would be (R - r)/R of their spacing at the
    // intrados and (R + r)/R at the extrados (0.58 and 2.9 mm at the defaults, R/r = 1.5; the
    // short intrados edges crumpled in the coupled runs). Instead the line from node i of the
    // arch's first ring to node i of its last (the same angle in the transported frame) gets
    // nodes 0.866 h apart along its own length, and neighbouring lines are stitched in order of
    // the centreline coordinate s.
    std::vector<double> st = meridian_stations(curve, 0, s_arch0, 0.866 * h, 4);
    const std::vector<double> st_after = meridian_stations(curve, s_arch1, s_end, 0.866 * h, 4);
    st.insert(st.end(), st_after.begin(), st_after.end());
    std::vector<Tri> tris;
    std::vector<double> tri_s;  // the centreline coordinate of every triangle
    std::vector<double> node_s;  // of every node
    Ring prev = copy_ring(aorta, plane, aortic_ring, kAnchor | kAorticAnnulus);
    node_s.assign(aorta.node_count(), 0.0);
    double s_prev = 0;
    for (std::size_t k = 1; k < st.size(); ++k) {
      const double s = st[k];
      Vec3 f1, f2;
      frame(s, f1, f2);
      const std::uint32_t tags = s >= s_outflow - 1e-9 ? kOutflow : kRegionNone;
      Ring ring = add_ring(aorta, ring_count(mean_radius(s), h), centre(s), f1, f2,
                           [&](double th) { return radius(s, th); }, tags);
      node_s.resize(aorta.node_count(), s);
      if (s <= s_arch0)  // at the root the frame is (x, y): ring angles are azimuths about A
        for (std::size_t i = 0; i < ring.node.size(); ++i)
          if (s <= crown_hold_height(ring.angle[i])) aorta.region[ring.node[i]] |= kAnchor | kAorticAnnulus;
      const std::size_t before = tris.size();
      if (s_prev == s_arch0 && s == s_arch1) {
        // the arch: ring prev (at s_arch0) to ring (at s_arch1), both of the tube's radius and
        // the same node count (ring_count(r_arch, h)), node i of each at the same angle
        const std::size_t n = ring.node.size();
        std::vector<std::vector<std::int32_t>> line(n);
        std::vector<std::vector<double>> line_s(n);
        const int dense = 400;
        for (std::size_t i = 0; i < n; ++i) {
          const double th = ring.angle[i];
          auto point = [&](double sa) {
            Vec3 e1, e2;
            frame(sa, e1, e2);
            return Vec3(centre(sa) + r_arch * (std::cos(th) * e1 + std::sin(th) * e2));
          };
          std::vector<double> param(dense + 1), arc(dense + 1, 0.0);
          for (int q = 0; q <= dense; ++q) {
            param[q] = s_arch0 + (s_arch1 - s_arch0) * q / dense;
            if (q) arc[q] = arc[q - 1] + (point(param[q]) - point(param[q - 1])).norm();
          }
          const int segments = std::max(1, static_cast<int>(std::lround(arc.back() / (0.866 * h))));
          const std::vector<double> at = detail::equal_arclength_stations(param, arc, segments);
          line[i].push_back(prev.node[i]);
          line_s[i].push_back(s_arch0);
          for (int q = 1; q < segments; ++q) {
            line[i].push_back(aorta.add_node(point(at[q]), kRegionNone));
            line_s[i].push_back(at[q]);
            node_s.push_back(at[q]);
          }
          line[i].push_back(ring.node[i]);
          line_s[i].push_back(s_arch1);
        }
        for (std::size_t i = 0; i < n; ++i) {  // the strip between line i and line i + 1
          const auto& a = line[i];
          const auto& b = line[(i + 1) % n];
          const auto& sa = line_s[i];
          const auto& sb = line_s[(i + 1) % n];
          std::size_t p = 0, q = 0;
          while (p + 1 < a.size() || q + 1 < b.size()) {
            const bool along_a = q + 1 >= b.size() || (p + 1 < a.size() && sa[p + 1] <= sb[q + 1]);
            if (along_a) {
              tris.push_back({a[p], a[p + 1], b[q]});
              ++p;
            } else {
              tris.push_back({a[p], b[q + 1], b[q]});
              ++q;
            }
          }
        }
      } else {
        detail::stitch_rings(prev, ring, tris);
      }
      for (std::size_t t = before; t < tris.size(); ++t)
        tri_s.push_back((node_s[tris[t][0]] + node_s[tris[t][1]] + node_s[tris[t][2]]) / 3);
      s_prev = s;
      prev = std::move(ring);
    }
    // every triangle's normal away from the centreline (the rings' bands are so by
    // construction; the arch's strips are made so here), then all into the lumen below
    for (std::size_t t = 0; t < tris.size(); ++t) {
      const Vec3& x0 = aorta.position_mm[tris[t][0]];
      const Vec3 nrm = (aorta.position_mm[tris[t][1]] - x0).cross(aorta.position_mm[tris[t][2]] - x0);
      const Vec3 mid = (x0 + aorta.position_mm[tris[t][1]] + aorta.position_mm[tris[t][2]]) / 3;
      if (nrm.dot(mid - centre(tri_s[t])) < 0) std::swap(tris[t][1], tris[t][2]);
    }
    add_triangles(aorta, tris, Tissue::kAorticWall, g.aorta_wall_mm);
    // Orientation: normals into the lumen.
    {
      const std::size_t tr = aorta.triangle_count() / 2;
      if (aorta.unit_normal(tr).dot(centre(tri_s[tr]) - aorta.centroid(tr)) < 0) aorta.flip_orientation();
    }
    // Fibres: circumferential about the local centreline.
    for (std::size_t tr = 0; tr < aorta.triangle_count(); ++tr) {
      const double s = tri_s[tr];
      const Vec3 circ = tangent(s).cross(aorta.centroid(tr) - centre(s));
      aorta.fibre[tr] = tangent_in_triangle(aorta, tr, circ, Vec3::UnitX());
    }
  }
  heart.outflow = {centre(s_outflow), centre(s_end), r_desc};

  // ---- assemble in body order, centre in the fluid box ------------------------------------
  std::vector<TriMesh> leaflets = std::move(heart.bodies);
  heart.bodies.clear();
  heart.bodies.push_back(std::move(plane));
  heart.bodies.push_back(std::move(lv));
  heart.bodies.push_back(std::move(la));
  for (auto& b : leaflets) heart.bodies.push_back(std::move(b));
  heart.bodies.push_back(std::move(aorta));

  Vec3 lo = Vec3::Constant(1e300), hi = Vec3::Constant(-1e300);
  for (const auto& b : heart.bodies)
    for (const auto& p : b.position_mm) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  const Vec3 box(fluid.box_x_mm, fluid.box_y_mm, fluid.box_z_mm);
  const Vec3 offset = 0.5 * box - 0.5 * (lo + hi);
  lay.box_clearance_mm = 0.5 * (box - (hi - lo));
  {
    const Vec3 need = (hi - lo).array() + 2 * kMinBoxClearanceMm;
    const char* axis[3] = {"x", "y", "z"};
    for (int d = 0; d < 3; ++d)
      require(lay.box_clearance_mm[d] >= kMinBoxClearanceMm,
              std::string("the heart spans ") + num(hi[d] - lo[d]) + " mm in " + axis[d] + " but fluid.box_" +
                  axis[d] + "_mm = " + num(box[d]) + " (need >= " + num(need[d]) +
                  " for a " + num(kMinBoxClearanceMm) + " mm clearance); enlarge the box or reduce "
                  "geometry.lv_long_axis_mm / lv_short_axis_mm / aortic_*_diameter_mm / la_volume_ml");
  }
  for (auto& b : heart.bodies) {
    for (auto& p : b.position_mm) p += offset;
    for (auto& p : b.rest_position_mm) p += offset;
  }
  heart.plane.z_mm += offset.z();
  heart.plane.centre_mm += offset;
  heart.plane.mitral_centre_mm += offset;
  heart.plane.aortic_centre_mm += offset;
  heart.outflow.start_mm += offset;
  heart.outflow.end_mm += offset;

  // ---- verify -------------------------------------------------------------------------------
  std::vector<QualityIssue> issues;
  CheckOptions options;
  options.plane_z_mm = heart.plane.z_mm;
  options.plane_tolerance_mm = 1e-9 * (1 + std::abs(heart.plane.z_mm));
  options.degenerate_min_angle_deg = 0.1;
  options.aortic_crown_height_mm = lay.aortic_crown_height_mm;
  for (const auto& b : heart.bodies) {
    auto bi = check_body(b, options);
    issues.insert(issues.end(), bi.begin(), bi.end());
  }
  auto xi = check_intersections(heart.body_pointers());
  issues.insert(issues.end(), xi.begin(), xi.end());
  // LV vs LA and aorta: they lie on opposite sides of the rigid plane, which separates them
  // where they meet it; their gap is measured outside a band of kPlaneBandMm around it (ours).
  struct Pair {
    std::string_view p, q;
    double band;
  };
  const Pair unattached[] = {{kLvBody, kLaBody, kPlaneBandMm},
                             {kLvBody, kAortaBody, kPlaneBandMm},
                             {kLaBody, kAortaBody, -1}};
  for (const auto& [p, q, band] : unattached) {
    const double gap = min_gap_mm(heart.body(p), heart.body(q), kMinBodyGapMm, heart.plane.z_mm, band);
    if (gap < kMinBodyGapMm)
      issues.push_back({"clearance", std::string(p),
                        "bodies '" + std::string(p) + "' and '" + std::string(q) + "' come within " + num(gap) +
                            " mm of each other (minimum " + num(kMinBodyGapMm) + " mm)"});
  }
  throw_if_issues(issues, "the geometry variant does not give a valid heart");
  return heart;
}

}  // namespace systole::geometry
