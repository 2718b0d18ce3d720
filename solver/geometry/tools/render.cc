#include "solver/geometry/tools/render.h"

#include <png.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

namespace systole::geometry::render {

namespace {

using Rgb = std::array<double, 3>;

Rgb tissue_colour(Tissue t) {
  switch (t) {
    case Tissue::kValvularPlane: return {0.62, 0.62, 0.62};
    case Tissue::kLvMyocardium: return {0.85, 0.45, 0.42};
    case Tissue::kLaMyocardium: return {0.66, 0.55, 0.82};
    case Tissue::kMitralLeaflet: return {0.95, 0.82, 0.30};
    case Tissue::kAorticLeaflet: return {0.98, 0.60, 0.18};
    case Tissue::kAorticWall: return {0.50, 0.70, 0.88};
    case Tissue::kVeinOstium: return {0.10, 0.20, 0.65};
  }
  return {1, 1, 1};
}

// Node colour for tagged nodes (the first matching tag wins); false if untagged.
bool region_colour(std::uint32_t r, Rgb& c) {
  if (r & kHisBundle) c = {0.10, 0.80, 0.20};
  else if (r & kBachmannBundle) c = {0.00, 0.85, 0.90};
  else if (r & kPvOstiumAny) c = {0.10, 0.20, 0.65};
  else if (r & kOutflow) c = {0.80, 0.15, 0.80};
  else if (r & (kLvApexRing | kLvBaseRing | kLvApex)) c = {1.0, 1.0, 1.0};
  else if (r & kFreeEdge) c = {0.80, 0.05, 0.05};
  else if (r & kAnchor) c = {0.12, 0.12, 0.12};
  else return false;
  return true;
}

struct Canvas {
  int w, h;
  std::vector<Rgb> px;
  std::vector<double> depth;
  Canvas(int w_, int h_) : w(w_), h(h_), px(w_ * h_, Rgb{1, 1, 1}), depth(w_ * h_, std::numeric_limits<double>::infinity()) {}
};

}  // namespace

void render_png(const std::filesystem::path& path, const std::vector<const TriMesh*>& bodies,
                const std::vector<View>& views, int panel) {
  Canvas canvas(panel * static_cast<int>(views.size()), panel);
  for (std::size_t v = 0; v < views.size(); ++v) {
    const View& view = views[v];
    const Vec3 f = view.forward.normalized();
    const Vec3 u = (view.up - view.up.dot(f) * f).normalized();
    const Vec3 r = f.cross(u);
    std::vector<const TriMesh*> shown;
    for (const TriMesh* m : bodies)
      if (view.bodies.empty() || std::find(view.bodies.begin(), view.bodies.end(), m->name) != view.bodies.end())
        shown.push_back(m);
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (const TriMesh* m : shown)
      for (const auto& p : m->position_mm) {
        xmin = std::min(xmin, p.dot(r));
        xmax = std::max(xmax, p.dot(r));
        ymin = std::min(ymin, p.dot(u));
        ymax = std::max(ymax, p.dot(u));
      }
    const double scale = 0.92 * panel / std::max(xmax - xmin, ymax - ymin);
    const double ox = v * panel + 0.5 * panel - 0.5 * (xmin + xmax) * scale;
    const double oy = 0.5 * panel + 0.5 * (ymin + ymax) * scale;
    auto project = [&](const Vec3& p) { return Vec3(ox + p.dot(r) * scale, oy - p.dot(u) * scale, p.dot(f)); };
    const int x_lo = static_cast<int>(v) * panel, x_hi = x_lo + panel;
    const Vec3 light = (-f + 0.4 * u - 0.3 * r).normalized();
    for (const TriMesh* m : shown) {
      std::vector<Vec3> q(m->node_count());
      std::vector<Rgb> node_col(m->node_count());
      std::vector<char> tagged(m->node_count());
      for (std::size_t i = 0; i < m->node_count(); ++i) {
        q[i] = project(m->position_mm[i]);
        tagged[i] = region_colour(m->region[i], node_col[i]);
      }
      for (std::size_t t = 0; t < m->triangle_count(); ++t) {
        const auto& tri = m->tri[t];
        const Vec3 &a = q[tri[0]], &b = q[tri[1]], &c = q[tri[2]];
        const double area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
        if (std::abs(area) < 1e-12) continue;
        const double shade = 0.35 + 0.65 * std::abs(m->unit_normal(t).dot(light));
        Rgb col[3];
        for (int k = 0; k < 3; ++k) col[k] = tagged[tri[k]] ? node_col[tri[k]] : tissue_colour(m->tissue[t]);
        if (m->tissue[t] == Tissue::kVeinOstium) col[0] = col[1] = col[2] = tissue_colour(Tissue::kVeinOstium);
        const int x0 = std::max(x_lo, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
        const int x1 = std::min(x_hi - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
        const int y0 = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
        const int y1 = std::min(panel - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            const double px = x + 0.5, py = y + 0.5;
            const double w0 = ((b.x() - px) * (c.y() - py) - (b.y() - py) * (c.x() - px)) / area;
            const double w1 = ((c.x() - px) * (a.y() - py) - (c.y() - py) * (a.x() - px)) / area;
            const double w2 = 1 - w0 - w1;
            if (w0 < 0 || w1 < 0 || w2 < 0) continue;
            const double d = w0 * a.z() + w1 * b.z() + w2 * c.z();
            const int idx = y * canvas.w + x;
            if (d >= canvas.depth[idx]) continue;
            canvas.depth[idx] = d;
            for (int k = 0; k < 3; ++k)
              canvas.px[idx][k] = shade * (w0 * col[0][k] + w1 * col[1][k] + w2 * col[2][k]);
          }
      }
      if (!view.fibres || m->kind == BodyKind::kRigid) continue;
      // Fibre strokes on a spatially thinned subset of triangles (about one per 9 mm^2).
      double acc = 0;
      const double stroke_mm = 2.6;
      for (std::size_t t = 0; t < m->triangle_count(); ++t) {
        acc += m->area_mm2(t);
        if (acc < 9.0) continue;
        acc = 0;
        const Vec3 cen = m->centroid(t);
        const Vec3 p0 = project(cen - 0.5 * stroke_mm * m->fibre[t]), p1 = project(cen + 0.5 * stroke_mm * m->fibre[t]);
        const int steps = static_cast<int>(std::ceil((p1 - p0).head<2>().norm() * 2)) + 1;
        for (int s = 0; s <= steps; ++s) {
          const Vec3 p = p0 + (p1 - p0) * (static_cast<double>(s) / steps);
          const int x = static_cast<int>(p.x()), y = static_cast<int>(p.y());
          if (x < x_lo || x >= x_hi || y < 0 || y >= panel) continue;
          const int idx = y * canvas.w + x;
          if (p.z() > canvas.depth[idx] + 0.6) continue;  // hidden
          canvas.px[idx] = {0.08, 0.08, 0.08};
        }
      }
    }
    // Panel separator.
    for (int y = 0; y < panel; ++y) canvas.px[y * canvas.w + x_lo] = {0.3, 0.3, 0.3};
  }
  std::FILE* fp = std::fopen(path.string().c_str(), "wb");
  if (!fp) throw std::runtime_error("cannot write " + path.string());
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    std::fclose(fp);
    throw std::runtime_error("libpng failed writing " + path.string());
  }
  png_init_io(png, fp);
  png_set_IHDR(png, info, canvas.w, canvas.h, 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  std::vector<unsigned char> row(3 * canvas.w);
  for (int y = 0; y < canvas.h; ++y) {
    for (int x = 0; x < canvas.w; ++x)
      for (int k = 0; k < 3; ++k)
        row[3 * x + k] = static_cast<unsigned char>(std::clamp(canvas.px[y * canvas.w + x][k], 0.0, 1.0) * 255 + 0.5);
    png_write_row(png, row.data());
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(fp);
}

}  // namespace systole::geometry::render
