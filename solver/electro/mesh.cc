#include "solver/electro/mesh.h"

#include <cmath>
#include <numbers>
#include <numeric>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::electro {
namespace {

int steps_for(double size_mm, double spacing_mm, const char* what) {
  if (!(size_mm > 0) || !(spacing_mm > 0) || spacing_mm > size_mm) {
    std::ostringstream os;
    os << what << ": size " << size_mm << " mm and spacing " << spacing_mm
       << " mm must be positive with spacing <= size";
    throw InputError(os.str());
  }
  return std::max(1, static_cast<int>(std::lround(size_mm / spacing_mm)));
}

Vec3 planar_fibre(double angle_deg) {
  const double a = angle_deg * std::numbers::pi / 180.0;
  return Vec3(std::cos(a), std::sin(a), 0.0);
}

}  // namespace

void ElectroMesh::check() const {
  const std::size_t n = node_count();
  auto fail = [](const std::string& m) { throw InputError("electro mesh: " + m); };
  if (cell_dim != 2 && cell_dim != 3) fail("cell_dim must be 2 or 3");
  if (node_region.size() != n || node_domain.size() != n) fail("per-node arrays disagree in size");
  if (fibre.size() != cell.size()) fail("one fibre per cell required");
  if (n == 0 || cell.empty()) fail("empty mesh");
  for (std::size_t c = 0; c < cell.size(); ++c) {
    for (int k = 0; k < nodes_per_cell(); ++k)
      if (cell[c][k] < 0 || static_cast<std::size_t>(cell[c][k]) >= n) fail("cell node index out of range");
    if (std::abs(fibre[c].norm() - 1.0) > 1e-6) fail("fibre of cell " + std::to_string(c) + " is not a unit vector");
  }
  for (auto d : node_domain)
    if (d >= domain_names.size()) fail("node domain index without a domain name");
}

std::vector<std::int32_t> ElectroMesh::components() const {
  std::vector<std::int32_t> parent(node_count());
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::int32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (const auto& c : cell)
    for (int k = 1; k < nodes_per_cell(); ++k) parent[find(c[k])] = find(c[0]);
  std::vector<std::int32_t> label(node_count(), -1), out(node_count());
  std::int32_t next = 0;
  for (std::size_t i = 0; i < node_count(); ++i) {
    const std::int32_t r = find(static_cast<std::int32_t>(i));
    if (label[r] < 0) label[r] = next++;
    out[i] = label[r];
  }
  return out;
}

ElectroMesh make_sheet(double size_x_mm, double size_y_mm, double spacing_mm, double fibre_angle_deg) {
  const int nx = steps_for(size_x_mm, spacing_mm, "sheet x"), ny = steps_for(size_y_mm, spacing_mm, "sheet y");
  ElectroMesh m;
  m.cell_dim = 2;
  auto id = [&](int i, int j) { return static_cast<std::int32_t>(j * (nx + 1) + i); };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) m.position_mm.emplace_back(size_x_mm * i / nx, size_y_mm * j / ny, 0.0);
  const Vec3 f = planar_fibre(fibre_angle_deg);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const auto a = id(i, j), b = id(i + 1, j), c = id(i + 1, j + 1), d = id(i, j + 1);
      if ((i + j) % 2 == 0) {
        m.cell.push_back({a, b, c, -1});
        m.cell.push_back({a, c, d, -1});
      } else {
        m.cell.push_back({a, b, d, -1});
        m.cell.push_back({b, c, d, -1});
      }
      m.fibre.push_back(f);
      m.fibre.push_back(f);
    }
  m.node_region.assign(m.node_count(), 0);
  m.node_domain.assign(m.node_count(), 0);
  m.domain_names = {"sheet"};
  return m;
}

ElectroMesh make_slab(double sx_mm, double sy_mm, double sz_mm, double spacing_mm, double fibre_angle_deg) {
  const int nx = steps_for(sx_mm, spacing_mm, "slab x"), ny = steps_for(sy_mm, spacing_mm, "slab y"),
            nz = steps_for(sz_mm, spacing_mm, "slab z");
  ElectroMesh m;
  m.cell_dim = 3;
  auto id = [&](int i, int j, int k) { return static_cast<std::int32_t>((k * (ny + 1) + j) * (nx + 1) + i); };
  for (int k = 0; k <= nz; ++k)
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i)
        m.position_mm.emplace_back(sx_mm * i / nx, sy_mm * j / ny, sz_mm * k / nz);
  const Vec3 f = planar_fibre(fibre_angle_deg);
  // Kuhn split: the 6 monotone paths from corner (0,0,0) to (1,1,1).
  static const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (const auto& p : perms) {
          int c[3] = {i, j, k};
          std::array<std::int32_t, 4> t{};
          t[0] = id(c[0], c[1], c[2]);
          for (int s = 0; s < 3; ++s) {
            ++c[p[s]];
            t[s + 1] = id(c[0], c[1], c[2]);
          }
          m.cell.push_back(t);
          m.fibre.push_back(f);
        }
  m.node_region.assign(m.node_count(), 0);
  m.node_domain.assign(m.node_count(), 0);
  m.domain_names = {"slab"};
  return m;
}

ElectroMesh from_surfaces(const std::vector<const geometry::TriMesh*>& bodies) {
  ElectroMesh m;
  m.cell_dim = 2;
  for (std::size_t b = 0; b < bodies.size(); ++b) {
    const geometry::TriMesh& body = *bodies[b];
    std::vector<std::int32_t> new_index(body.node_count(), -1);
    for (std::size_t t = 0; t < body.triangle_count(); ++t) {
      const geometry::Tissue tissue = body.tissue[t];
      if (tissue != geometry::Tissue::kLvMyocardium && tissue != geometry::Tissue::kLaMyocardium) continue;
      std::array<std::int32_t, 4> c{-1, -1, -1, -1};
      for (int k = 0; k < 3; ++k) {
        const auto old = body.tri[t][k];
        if (new_index[old] < 0) {
          new_index[old] = static_cast<std::int32_t>(m.node_count());
          m.position_mm.push_back(body.position_mm[old]);
          m.node_region.push_back(body.region[old]);
          m.node_domain.push_back(static_cast<std::uint8_t>(b));
          m.source_node.push_back({static_cast<std::int32_t>(b), old});
        }
        c[k] = new_index[old];
      }
      m.cell.push_back(c);
      Vec3 f = body.fibre[t];
      // A missing fibre (zero vector) falls back to the first edge direction (ours).
      if (f.norm() < 1e-12) f = body.position_mm[body.tri[t][1]] - body.position_mm[body.tri[t][0]];
      m.fibre.push_back(f.normalized());
    }
    m.domain_names.push_back(body.name);
  }
  return m;
}

}  // namespace systole::electro
