#pragma once
// Lagrangian markers of the immersed boundary (MODEL.md §4): one marker per tile of a
// quadratically tiled triangle mesh (geometry::tile), at the tile's centroid, carrying the
// tile's area, unit normal, velocity and owning body. The forcing volume of a marker is
// ΔV = A·h (eq 7), h = (Δx Δy Δz)^{1/3} (ours for a non-cubic cell; = Δ on the seed's grids).
//
// Contract
// - Positions are nondimensional (grid units, d_m): a body is given in millimetres with the
//   length scale mm_per_unit (24 mm = d_m in the seed) and converted once at construction.
// - Every rank holds every marker (replicated, ours): markers are few next to grid cells
//   (≈ 10⁵ for the heart vs ≈ 10⁷ cells), and replication keeps spreading race-free and
//   bitwise equal between 1 and 2 ranks (see transfer.h for who computes what).
// - A body's tiled nodes are the state; markers are recomputed from them by update() (after a
//   prescribed motion, or after the caller moved the nodes).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solver/geometry/tri_mesh.h"
#include "solver/grid/grid.h"

namespace systole::ibm {

using Vec3 = Eigen::Vector3d;

// Which side of the surface the blood wets (MODEL.md §4): closed surfaces take their load
// from the side their normal points into; leaflets are wet on both sides (eq 12).
enum class Sides { one, two };
// The orientation the body's normals must have, checked at construction (bad input test).
enum class ExpectedNormals {
  outward,    // out of the enclosed volume (a sphere in a stream: the blood is outside)
  inward,     // into the enclosed volume (chambers, vessels: the blood is inside)
  unchecked,  // open sheets (leaflets, plates)
};

struct BodyOptions {
  double mm_per_unit = 24.0;       // length scale: 1 nondimensional unit = d_m = 24 mm (seed)
  int tiling_level = 0;            // m of the quadratic tiling; 0: the smallest m with tile
                                   // edges <= spacing_fraction · h (MODEL.md §4)
  double spacing_fraction = 0.7;   // target marker spacing / Eulerian spacing (seed 0.7)
  Sides sides = Sides::one;
  ExpectedNormals normals = ExpectedNormals::unchecked;
  bool rigid = true;               // rigid: moved only by set_rigid_motion()/advance_rigid()
  // Retraction r_d (ours, after Breugem 2012 J. Comput. Phys. 231:4469, §2.3 and §3.1, r_d ≈ 0.3):
  // the forcing point of each marker is moved off the surface, away from the blood, by
  // r_d·h along the normal (X = centroid − r_d h n), in [0, 1]. The diffuse forcing acts over
  // ≈ ±h around the markers and makes the body look thicker by a fraction of h; retracting the
  // markers compensates it to leading order. One-sided bodies only (a two-sided leaflet has
  // blood on both sides: r_d must be 0). The loads' probes stay at the surface + h n.
  double retraction_cells = 0.0;
};

struct Body {
  std::string name;
  BodyOptions options;
  geometry::TriMesh tiled;          // the tiled mesh, positions in nondimensional units
                                    // (stored in position_mm despite the name: see contract)
  std::vector<Vec3> node_velocity;  // nondimensional, per tiled node
  std::size_t first_marker = 0, marker_count = 0;
  bool active = true;               // false: its markers exert no forcing (vein ostia, §2)
  // Prescribed rigid motion: V(x) = velocity + angular_velocity × (x − centre).
  Vec3 velocity = Vec3::Zero(), angular_velocity = Vec3::Zero(), centre = Vec3::Zero();
  int tiling_level = 1;             // the m used
};

// All markers, structure of arrays, nondimensional.
struct MarkerArrays {
  // position: the forcing point (the tile centroid, moved by −r_d h n when the body's
  // retraction_cells r_d > 0); surface: the tile centroid on the surface (the loads' base).
  std::vector<Vec3> position, surface, normal, velocity;
  std::vector<double> area;                      // tile area
  std::vector<std::int32_t> body;                // index into Markers::bodies()
  std::vector<std::array<std::int32_t, 3>> node; // the tile's nodes in its body's tiled mesh
  std::size_t size() const { return position.size(); }
};

class Markers {
 public:
  explicit Markers(const grid::Grid& grid);

  // Tiles `mesh_mm`, converts to grid units, checks it, appends its markers; returns the body
  // index. Throws InputError when a marker lies outside the box (x, y in [0, L], z in
  // [Δz, Lz − Δz]: the MLS support must stay inside the walls) or when the normals are
  // inverted (signed enclosed volume of the wrong sign for options.normals). Adds a warning
  // (warnings()) when the tiled markers are coarser than the grid, naming the tiling level
  // that would fix it.
  int add_body(const geometry::TriMesh& mesh_mm, const std::string& name, const BodyOptions& options);

  // Switch a body's forcing off/on (MODEL.md §2: the pulmonary-vein ostia close in atrial
  // systole). Inactive markers are skipped by interpolation, forcing and loads.
  void set_active(int body, bool active) { bodies_.at(body).active = active; }
  // Prescribed rigid motion of a body (nondimensional): sets the node velocities.
  void set_rigid_motion(int body, const Vec3& velocity, const Vec3& angular_velocity, const Vec3& centre);
  // Moves every body's nodes by its rigid motion over dt (translation + rotation about the
  // centre, exact for constant motion; the centre moves with the body), then update().
  void advance_rigid(double dt);
  // Sets a deformable body's tiled node positions and velocities (grid units), then update().
  void set_nodes(int body, const std::vector<Vec3>& position, const std::vector<Vec3>& velocity);

  // Recomputes marker position, normal, area, velocity from the bodies' nodes (every body, or
  // one: set_nodes touches only its own body's markers).
  void update();
  void update(int body);

  const MarkerArrays& markers() const { return m_; }
  const std::vector<Body>& bodies() const { return bodies_; }
  std::size_t size() const { return m_.size(); }
  bool active(std::size_t marker) const { return bodies_[m_.body[marker]].active; }
  // h of eq 7 and the forcing volume ΔV = A·h of a marker.
  double h() const { return h_; }
  double forcing_volume(std::size_t marker) const { return m_.area[marker] * h_; }
  const std::vector<std::string>& warnings() const { return warnings_; }
  const grid::Grid& grid() const { return grid_; }

 private:
  void check_body(const Body& b) const;
  grid::Grid grid_;
  double h_;
  std::vector<Body> bodies_;
  MarkerArrays m_;
  std::vector<std::string> warnings_;
};

// Signed volume enclosed by a triangle mesh, (1/6) Σ c·(b−a)×(c−a)... about the node centroid:
// positive when the normals point outward. Meaningful for closed (or nearly closed) surfaces.
double signed_volume(const geometry::TriMesh& mesh);

}  // namespace systole::ibm
