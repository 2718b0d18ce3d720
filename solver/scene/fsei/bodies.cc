#include "solver/scene/fsei/bodies.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>

#include "solver/core/units.h"
#include "solver/scene/chamber_walls.h"
#include "solver/scene/fsei/scales.h"

namespace systole::scene::fsei {
namespace {

using geometry::Vec3;

// A sub-mesh with the same nodes and the triangles `keep` selects (the LA wall and its vein caps
// become separate marker bodies that share the shell's nodes).
geometry::TriMesh select_triangles(const geometry::TriMesh& mesh, const std::string& name,
                                   const std::function<bool(std::size_t)>& keep) {
  geometry::TriMesh out;
  out.name = name;
  out.kind = mesh.kind;
  out.position_mm = mesh.position_mm;
  out.region = mesh.region;
  for (std::size_t t = 0; t < mesh.triangle_count(); ++t) {
    if (!keep(t)) continue;
    out.tri.push_back(mesh.tri[t]);
    out.tissue.push_back(mesh.tissue[t]);
    out.thickness_mm.push_back(mesh.thickness_mm[t]);
    out.fibre.push_back(mesh.fibre[t]);
  }
  return out;
}

bool is_cusp(std::string_view name) {
  return std::find(std::begin(geometry::kAorticCuspBodies), std::end(geometry::kAorticCuspBodies), name) !=
         std::end(geometry::kAorticCuspBodies);
}

// The limits and anchors of one body's shell (ours unless said): the seed's mitral limiter (no
// chordae: towards the atrium, -z, from the built closed valve; the scene switches it over the
// phases [0, structure.mitral_limiter_end_phase) of every beat, valve_switches.h), the open
// cusps kept off the sinus wall (structure.aortic_cusp_radius_limit), the Darcy outlet held
// (fsei.aorta.outlet_held: anchored to the plane alone, the descending aorta's free end drifted
// 3 mm into the box's wall by 111 ms; docs/notes/fsei-notebook.md).
void constrain_body(const config::Scenario& s, const geometry::LeftHeart& heart, std::string_view name,
                    structure::ShellModel& model) {
  const bool mitral = name == geometry::kMitralAnteriorBody || name == geometry::kMitralPosteriorBody;
  if (mitral && s.structure.mitral_limiter)
    model.set_displacement_limit(-Vec3::UnitZ(), s.structure.mitral_limit_mm, heart.body(name).position_mm);
  if (is_cusp(name) && s.structure.aortic_cusp_radius_limit > 0)
    model.set_radial_limit(heart.plane.aortic_centre_mm, heart.lv_axis_direction,
                           s.structure.aortic_cusp_radius_limit * heart.plane.aortic_radius_mm);
  if (name == geometry::kAortaBody && s.fsei.aorta.outlet_held) {
    const geometry::TriMesh& aorta = heart.body(name);
    std::vector<std::int32_t> outlet;
    for (std::size_t i = 0; i < aorta.node_count(); ++i)
      if (aorta.region[i] & geometry::kOutflow) outlet.push_back(static_cast<std::int32_t>(i));
    model.fix_nodes(outlet);
  }
}

// The tiling level of a body (ours): the mean tile edge <= 0.7 h (the seed's "marker spacing
// ≈ 0.7 h") and the longest <= h (no marker coarser than the grid), so a mesh with a few long
// edges is not over-refined everywhere as by ibm::Markers' own rule (every tile edge <= 0.7 h:
// 264 k instead of 145 k markers at coarse, the LV pressure at 16 ms within 0.01 %).
int marker_tiling_level(const geometry::TriMesh& mesh, double h_mm) {
  double sum = 0, longest = 0;
  for (const auto& t : mesh.tri)
    for (int k = 0; k < 3; ++k) {
      const double l = (mesh.position_mm[t[k]] - mesh.position_mm[t[(k + 1) % 3]]).norm();
      sum += l;
      longest = std::max(longest, l);
    }
  const double mean = sum / (3.0 * static_cast<double>(mesh.tri.size()));
  return std::max({1, static_cast<int>(std::ceil(longest / h_mm - 1e-12)),
                   static_cast<int>(std::ceil(mean / (0.7 * h_mm) - 1e-12))});
}

}  // namespace

const std::vector<std::string_view>& deformable_bodies() {
  static const std::vector<std::string_view> names{
      geometry::kLvBody,           geometry::kLaBody,           geometry::kMitralAnteriorBody,
      geometry::kMitralPosteriorBody, geometry::kAorticCuspBodies[0], geometry::kAorticCuspBodies[1],
      geometry::kAorticCuspBodies[2], geometry::kAortaBody};
  return names;
}

std::size_t shell_index(std::string_view body) {
  const auto& names = deformable_bodies();
  const auto it = std::find(names.begin(), names.end(), body);
  if (it == names.end()) throw std::logic_error("fsei: no shell for body " + std::string(body));
  return static_cast<std::size_t>(it - names.begin());
}

std::size_t shell_node_total(const structure::BodyGroup& group) {
  std::size_t n = 0;
  for (std::size_t b = 0; b < group.body_count(); ++b) n += group.body(b).node_count();
  return n;
}

structure::BodyGroup build_shells(const config::Scenario& s, const geometry::LeftHeart& heart) {
  const structure::ShellMaterials materials = chamber_wall_materials(s);
  const structure::ShellOptions wall = chamber_wall_options(s, heart.plane.z_mm);
  const structure::ShellOptions other = structure_options(s, heart.plane.z_mm);
  std::vector<structure::ShellModel> models;
  for (std::string_view name : deformable_bodies()) {
    const bool chamber = name == geometry::kLvBody || name == geometry::kLaBody;
    // (a mitral leaflet with a rest opening starts pre-strained at its built, closed shape)
    models.push_back(body_shell(heart.body(name), materials, chamber ? wall : other));
    constrain_body(s, heart, name, models.back());
  }
  return structure::BodyGroup(std::move(models), contact_options(s));
}

AortaPretension::AortaPretension(const config::Scenario& s, structure::BodyGroup& group)
    : ramp_ms_(s.fsei.aorta.pressure_ramp_ms) {
  const config::Fsei& fs = s.fsei;
  const bool prestressed = fs.aorta.pretension == "prestress" && fs.aorta.ground_pressure_mmhg > 0;
  // the wall's share of the ground pressure (fsei.aorta.prestress_fraction, ours): 1 with
  // prestress, 0 with the outer load; the outer load carries the rest
  wall_share_ = prestressed ? fs.aorta.prestress_fraction : 0.0;
  outer_kpa_ = (1 - wall_share_) * fs.aorta.ground_pressure_mmhg * units::kPaPerMmHg * 1e-3;
  if (!prestressed) return;
  // the wall's share inside on every triangle outside the Darcy outlet and none outside;
  // anchors and the held outlet take the reactions
  structure::ShellModel& aorta = group.body(shell_index(geometry::kAortaBody));
  const double p_kpa = wall_share_ * fs.aorta.ground_pressure_mmhg * units::kPaPerMmHg * 1e-3;
  prestress_ = structure::membrane_prestress(
      aorta, structure::pressure_nodal_forces(aorta.stress_free_mesh(), aorta.positions_mm(), -p_kpa, geometry::kOutflow));
  prestress_rest_mm_ = prestress_->rest_length_mm;
  for (const auto& sp : aorta.springs()) built_rest_mm_.push_back(sp.rest_length_mm);
  if (ramp_ms_ == 0) aorta.set_rest_lengths_mm(prestress_rest_mm_);
}

void AortaPretension::apply(double t_ms, const geometry::TriMesh& built_aorta, structure::ShellModel& aorta,
                            std::vector<Vec3>& f_mn) const {
  if (prestress_ && ramp_ms_ > 0) {  // the rest lengths go from the built ones to the prestressed
    const double r = std::min(1.0, t_ms / ramp_ms_);
    std::vector<double> l0(built_rest_mm_.size());
    for (std::size_t k = 0; k < l0.size(); ++k) l0[k] = built_rest_mm_[k] + r * (prestress_rest_mm_[k] - built_rest_mm_[k]);
    aorta.set_rest_lengths_mm(l0);
  }
  if (outer_kpa_ > 0) {
    // the follower load p A n_in / 3 on each node of each loaded triangle (n_in into the lumen:
    // the load pushes the wall inwards); the Darcy outflow's triangles (all three nodes tagged
    // kOutflow) carry none: there the blood's pressure falls to the outer fluid's, and an outer
    // load would squeeze the tube shut
    const double ramp = ramp_ms_ > 0 ? std::min(1.0, t_ms / ramp_ms_) : 1.0;
    const std::vector<Vec3> load =
        structure::pressure_nodal_forces(built_aorta, aorta.positions_mm(), ramp * outer_kpa_, geometry::kOutflow);
    for (std::size_t i = 0; i < f_mn.size(); ++i) f_mn[i] += load[i];
  }
}

std::vector<Link> add_heart_markers(const config::Scenario& s, const geometry::LeftHeart& heart, ibm::Markers& markers) {
  {
    ibm::BodyOptions plane;
    plane.mm_per_unit = kDmMm;
    plane.rigid = true;
    plane.sides = ibm::Sides::two;
    markers.add_body(heart.body(geometry::kValvularPlaneBody), std::string(geometry::kValvularPlaneBody), plane);
  }
  std::vector<Link> links;
  const double h_mm = markers.h() * kDmMm;
  auto link = [&](const geometry::TriMesh& mesh, const std::string& name, std::size_t shell, bool two_sided, bool cap) {
    ibm::BodyOptions o;
    o.mm_per_unit = kDmMm;
    o.tiling_level = marker_tiling_level(mesh, h_mm);
    o.rigid = false;
    o.sides = two_sided ? ibm::Sides::two : ibm::Sides::one;
    Link l;
    l.marker_body = markers.add_body(mesh, name, o);
    l.shell = shell;
    l.map = geometry::tiling_map(mesh, markers.bodies()[static_cast<std::size_t>(l.marker_body)].tiling_level);
    l.cap = cap;
    links.push_back(std::move(l));
  };
  const auto& deformable = deformable_bodies();
  for (std::size_t b = 0; b < deformable.size(); ++b) {
    const geometry::TriMesh& mesh = heart.body(deformable[b]);
    const std::string name(deformable[b]);
    if (b == kLa) {
      auto is_cap = [&](std::size_t t) { return mesh.tissue[t] == geometry::Tissue::kVeinOstium; };
      link(select_triangles(mesh, name, [&](std::size_t t) { return !is_cap(t); }), name, b, false, false);
      const geometry::TriMesh caps = select_triangles(mesh, "pv_caps", is_cap);
      if (!caps.tri.empty()) link(caps, "pv_caps", b, true, true);
    } else {
      link(mesh, name, b, mesh.kind == geometry::BodyKind::kLeaflet, false);
    }
  }
  return links;
}

int marker_body_named(const ibm::Markers& markers, std::string_view name) {
  for (std::size_t k = 0; k < markers.bodies().size(); ++k)
    if (markers.bodies()[k].name == name) return static_cast<int>(k);
  throw std::logic_error("fsei: no marker body " + std::string(name));
}

}  // namespace systole::scene::fsei
