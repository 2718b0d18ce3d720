#include "solver/ibm/markers.h"

#include <cmath>
#include <sstream>

#include <Eigen/Geometry>

#include "solver/core/errors.h"
#include "solver/geometry/tiling.h"

namespace systole::ibm {

double signed_volume(const geometry::TriMesh& mesh) {
  Vec3 c = Vec3::Zero();
  for (const Vec3& p : mesh.position_mm) c += p;
  if (!mesh.position_mm.empty()) c /= static_cast<double>(mesh.position_mm.size());
  double v = 0;
  for (std::size_t t = 0; t < mesh.tri.size(); ++t) {
    const auto& n = mesh.tri[t];
    const Vec3 a = mesh.position_mm[n[0]] - c, b = mesh.position_mm[n[1]] - c, d = mesh.position_mm[n[2]] - c;
    v += a.dot(b.cross(d));
  }
  return v / 6.0;
}

Markers::Markers(const grid::Grid& grid) : grid_(grid), h_(std::cbrt(grid.cell_volume())) {}

int Markers::add_body(const geometry::TriMesh& mesh_mm, const std::string& name, const BodyOptions& o) {
  if (!(o.mm_per_unit > 0)) {
    std::ostringstream m;
    m << "ibm body '" << name << "': mm_per_unit = " << o.mm_per_unit << " must be > 0";
    throw InputError(m.str());
  }
  if (!(o.spacing_fraction > 0 && o.spacing_fraction <= 2)) {
    std::ostringstream m;
    m << "ibm body '" << name << "': spacing_fraction = " << o.spacing_fraction << " is out of range (0, 2]";
    throw InputError(m.str());
  }
  if (o.tiling_level < 0) {
    std::ostringstream m;
    m << "ibm body '" << name << "': tiling_level = " << o.tiling_level << " must be >= 0 (0: automatic)";
    throw InputError(m.str());
  }
  if (!(o.retraction_cells >= 0 && o.retraction_cells <= 1)) {
    std::ostringstream m;
    m << "ibm body '" << name << "': retraction_cells = " << o.retraction_cells << " is out of range [0, 1]";
    throw InputError(m.str());
  }
  if (o.retraction_cells > 0 && o.sides == Sides::two) {
    std::ostringstream m;
    m << "ibm body '" << name << "': retraction_cells = " << o.retraction_cells
      << " on a two-sided body (blood on both sides: there is no inside to retract into); use 0";
    throw InputError(m.str());
  }
  if (mesh_mm.tri.empty()) throw InputError("ibm body '" + name + "' has no triangles");
  mesh_mm.check_arrays();
  const double target_mm = o.spacing_fraction * h_ * o.mm_per_unit;  // tile edge target
  const int needed = geometry::tiling_level(mesh_mm, target_mm);
  const int level = o.tiling_level > 0 ? o.tiling_level : needed;
  Body b;
  b.name = name;
  b.options = o;
  b.tiling_level = level;
  b.tiled = geometry::tile(mesh_mm, level);
  for (Vec3& p : b.tiled.position_mm) p /= o.mm_per_unit;
  b.node_velocity.assign(b.tiled.node_count(), Vec3::Zero());
  check_body(b);
  const double max_edge = geometry::max_edge_mm(b.tiled);  // grid units now
  if (max_edge > h_) {
    std::ostringstream m;
    m << "ibm body '" << name << "': markers are coarser than the grid (longest tile edge " << max_edge
      << " > h = " << h_ << " at tiling level " << level << "); tiling_level = " << needed
      << " gives edges <= " << o.spacing_fraction << " h (MODEL.md §4)";
    warnings_.push_back(m.str());
  }
  b.first_marker = m_.size();
  b.marker_count = b.tiled.triangle_count();
  const int index = static_cast<int>(bodies_.size());
  for (std::size_t t = 0; t < b.tiled.triangle_count(); ++t) {
    m_.position.push_back(Vec3::Zero());
    m_.surface.push_back(Vec3::Zero());
    m_.normal.push_back(Vec3::Zero());
    m_.velocity.push_back(Vec3::Zero());
    m_.area.push_back(0);
    m_.body.push_back(index);
    m_.node.push_back(b.tiled.tri[t]);
  }
  bodies_.push_back(std::move(b));
  update();
  return index;
}

void Markers::check_body(const Body& b) const {
  const double lx = grid_.lx(), ly = grid_.ly(), lz = grid_.lz(), dz = grid_.dz();
  for (std::size_t n = 0; n < b.tiled.node_count(); ++n) {
    const Vec3& p = b.tiled.position_mm[n];
    if (!(p.x() >= 0 && p.x() <= lx && p.y() >= 0 && p.y() <= ly && p.z() >= dz && p.z() <= lz - dz)) {
      std::ostringstream m;
      m << "ibm body '" << b.name << "': node " << n << " at (" << p.x() << ", " << p.y() << ", " << p.z()
        << ") (grid units, = mm / " << b.options.mm_per_unit << ") is outside the box [0, " << lx << "] x [0, " << ly
        << "] x [" << dz << ", " << lz - dz << "] (one cell off the z walls: the MLS support must stay inside)";
      throw InputError(m.str());
    }
  }
  if (b.options.normals == ExpectedNormals::unchecked) return;
  const double v = signed_volume(b.tiled);
  const bool outward = b.options.normals == ExpectedNormals::outward;
  if ((outward && v <= 0) || (!outward && v >= 0)) {
    std::ostringstream m;
    m << "ibm body '" << b.name << "': inverted normals: the signed enclosed volume is " << v << " but the normals must point "
      << (outward ? "out of" : "into") << " the enclosed volume (flip the triangles' orientation)";
    throw InputError(m.str());
  }
}

void Markers::update() {
  for (std::size_t b = 0; b < bodies_.size(); ++b) update(static_cast<int>(b));
}

void Markers::update(int body) {
  const Body& b = bodies_.at(body);
  const auto& P = b.tiled.position_mm;
  const double retraction = b.options.retraction_cells * h_;
  for (std::size_t t = 0; t < b.marker_count; ++t) {
    const std::size_t q = b.first_marker + t;
    const auto& n = b.tiled.tri[t];
    const Vec3 av = (P[n[1]] - P[n[0]]).cross(P[n[2]] - P[n[0]]);
    const double two_a = av.norm();
    m_.surface[q] = (P[n[0]] + P[n[1]] + P[n[2]]) / 3.0;
    m_.area[q] = 0.5 * two_a;
    m_.normal[q] = two_a > 0 ? Vec3(av / two_a) : Vec3::Zero();
    m_.position[q] = m_.surface[q] - retraction * m_.normal[q];
    m_.velocity[q] = (b.node_velocity[n[0]] + b.node_velocity[n[1]] + b.node_velocity[n[2]]) / 3.0;
  }
}

void Markers::set_rigid_motion(int body, const Vec3& velocity, const Vec3& angular_velocity, const Vec3& centre) {
  Body& b = bodies_.at(body);
  b.velocity = velocity;
  b.angular_velocity = angular_velocity;
  b.centre = centre;
  for (std::size_t n = 0; n < b.tiled.node_count(); ++n)
    b.node_velocity[n] = velocity + angular_velocity.cross(b.tiled.position_mm[n] - centre);
  update();
}

void Markers::advance_rigid(double dt) {
  for (Body& b : bodies_) {
    if (!b.options.rigid) continue;
    const double w = b.angular_velocity.norm();
    const Eigen::Matrix3d R =
        w > 0 ? Eigen::AngleAxisd(w * dt, b.angular_velocity / w).toRotationMatrix() : Eigen::Matrix3d::Identity();
    for (std::size_t n = 0; n < b.tiled.node_count(); ++n) {
      Vec3& p = b.tiled.position_mm[n];
      p = b.centre + b.velocity * dt + R * (p - b.centre);
      b.node_velocity[n] = b.velocity + b.angular_velocity.cross(p - b.centre - b.velocity * dt);
    }
    b.centre += b.velocity * dt;
  }
  update();
}

void Markers::set_nodes(int body, const std::vector<Vec3>& position, const std::vector<Vec3>& velocity) {
  Body& b = bodies_.at(body);
  if (position.size() != b.tiled.node_count() || velocity.size() != b.tiled.node_count()) {
    std::ostringstream m;
    m << "ibm body '" << b.name << "': set_nodes got " << position.size() << " positions and " << velocity.size()
      << " velocities; the tiled mesh has " << b.tiled.node_count() << " nodes";
    throw InputError(m.str());
  }
  b.tiled.position_mm = position;
  b.node_velocity = velocity;
  update(body);
}

}  // namespace systole::ibm
