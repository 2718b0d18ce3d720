#pragma once
// The heart's bodies in the coupled scene: the thin shells of the deformable bodies (one
// structure::BodyGroup with contact), the aorta's pre-tension (MODEL.md §1: the ground pressure
// of the aortic root), and the immersed boundary's markers that the shells drive (the rigid
// valvular plane, every deformable body, the LA's vein caps apart).
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/tiling.h"
#include "solver/ibm/markers.h"
#include "solver/structure/contact.h"
#include "solver/structure/prestress.h"

namespace systole::scene::fsei {

// The deformable bodies in the order of the group's shells; the LV and LA come first.
const std::vector<std::string_view>& deformable_bodies();
constexpr std::size_t kLv = 0, kLa = 1;
std::size_t shell_index(std::string_view body);  // throws std::logic_error for another name

// The nodes of all the group's shells.
std::size_t shell_node_total(const structure::BodyGroup& group);

// The shells of the deformable bodies with the seed's mitral limiter (no chordae), the cusps'
// radial limit and the held Darcy outlet (ours), in one group with contact between them.
structure::BodyGroup build_shells(const config::Scenario& s, const geometry::LeftHeart& heart);

// The aorta's pre-tension (fsei.aorta.pretension): the ground pressure fsei.aorta.ground_pressure_mmhg
// carried by a pre-stress of the wall (its springs' rest lengths shortened so that the built
// shape is in equilibrium with the wall's share inside, structure/prestress.h) and/or by an
// outer pressure on the wall outside the Darcy region; either ramped over
// fsei.aorta.pressure_ramp_ms or there from t = 0.
class AortaPretension {
 public:
  // Sets the prestressed rest lengths on the group's aorta when there is no ramp.
  AortaPretension(const config::Scenario& s, structure::BodyGroup& group);
  bool prestressed() const { return prestress_.has_value(); }
  double wall_share() const { return wall_share_; }
  const std::optional<structure::Prestress>& prestress() const { return prestress_; }
  // The loads' transfer at time t_ms: the ramp's rest lengths, and the outer load added to the
  // aorta's nodal forces f_mn at its current positions.
  void apply(double t_ms, const geometry::TriMesh& built_aorta, structure::ShellModel& aorta,
             std::vector<geometry::Vec3>& f_mn) const;

 private:
  double ramp_ms_ = 0, wall_share_ = 0, outer_kpa_ = 0;
  std::optional<structure::Prestress> prestress_;
  std::vector<double> built_rest_mm_, prestress_rest_mm_;
};

// A marker body driven by one shell: the tiling map from the shell's nodes to the body's tiled
// nodes, and the loads' way back.
struct Link {
  int marker_body = -1;
  std::size_t shell = 0;
  geometry::TilingMap map;
  bool cap = false;  // a pulmonary-vein cap (switched on and off)
};

// Adds the rigid valvular plane and every deformable body to `markers` (the LA wall and its
// vein caps as separate bodies sharing the shell's nodes; leaflets and caps two-sided, walls
// one-sided) and returns the shells' links, in the order of the marker bodies after the plane.
std::vector<Link> add_heart_markers(const config::Scenario& s, const geometry::LeftHeart& heart, ibm::Markers& markers);

// The index of the marker body of that name; throws std::logic_error when there is none.
int marker_body_named(const ibm::Markers& markers, std::string_view name);

}  // namespace systole::scene::fsei
