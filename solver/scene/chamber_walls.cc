#include "solver/scene/chamber_walls.h"

#include "solver/core/errors.h"

namespace systole::scene {

structure::ShellMaterials chamber_wall_materials(const config::Scenario& s) {
  const config::Electromechanics& em = s.electromechanics;
  config::Tissue tissue = s.tissue;
  tissue.lv.fung_c_pa *= em.passive_stiffness_scale;
  tissue.la.fung_c_pa *= em.passive_stiffness_scale;
  if (em.isotropic_passive) {
    tissue.lv.alpha_c = tissue.lv.alpha_f;
    tissue.la.alpha_c = tissue.la.alpha_f;
  }
  return structure::materials_from_config(tissue);
}

structure::ShellOptions structure_options(const config::Scenario& s, double plane_z_mm) {
  structure::ShellOptions o;
  o.law = s.structure.law;
  o.membrane = s.structure.membrane;
  o.fung_exponent_cap = s.structure.fung_exponent_cap;
  o.fung_compression_fraction = s.structure.fung_compression_fraction;
  o.bending = s.structure.bending;
  o.damping_per_ms = s.structure.damping_per_ms;
  o.time_step_safety = s.structure.time_step_safety;
  o.strain_limit = s.structure.strain_limit;
  o.area_floor = s.structure.area_floor;
  o.area_floor_modulus_kpa = s.structure.area_floor_modulus_kpa;
  o.cavity_plane_z_mm = plane_z_mm;
  return o;
}

structure::ContactOptions contact_options(const config::Scenario& s) {
  structure::ContactOptions c;
  c.enabled = s.structure.contact;
  c.rule = s.structure.contact_rule == "cell_average" ? structure::ContactRule::kCellAverage
                                                      : structure::ContactRule::kPenalty;
  c.distance_mm = s.structure.contact_distance_mm;
  c.stiffness_kpa_per_mm = s.structure.contact_stiffness_kpa_per_mm;
  c.damping_ratio = s.structure.contact_damping_ratio;
  c.skin_mm = 0.5 * s.structure.contact_distance_mm;
  return c;
}

structure::ShellOptions chamber_wall_options(const config::Scenario& s, double plane_z_mm) {
  structure::ShellOptions o = structure_options(s, plane_z_mm);
  o.law = s.electromechanics.spring_law;
  o.bending = s.electromechanics.bending;
  o.active_min_fibre_stretch = s.tissue.active_min_fibre_stretch;
  o.active_cross_fibre_fraction = s.tissue.active_cross_fibre_fraction;
  return o;
}

structure::ShellModel body_shell(const geometry::TriMesh& built, const structure::ShellMaterials& materials,
                                 const structure::ShellOptions& options) {
  structure::ShellModel shell(geometry::rest_shape(built), materials, options);
  if (built.has_rest_shape()) {
    shell.set_state(built.position_mm, std::vector<structure::Vec3>(built.node_count(), structure::Vec3::Zero()));
    const double pre = shell.max_abs_strain();
    if (!(pre < options.strain_limit))
      throw InputError("body '" + built.name + "' starts pre-strained to |edge strain| " + std::to_string(pre) +
                       " at its built shape, beyond structure.strain_limit = " + std::to_string(options.strain_limit) +
                       ": reduce its rest shape's departure (geometry.mitral_rest_opening_mm)");
  }
  return shell;
}

void clear_passive_annulus(const geometry::TriMesh& mesh, double distance_mm, std::vector<std::int32_t>& ep_node) {
  if (distance_mm <= 0) return;
  std::vector<geometry::Vec3> ring;
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    if (mesh.region[i] & geometry::kAnchor) ring.push_back(mesh.position_mm[i]);
  for (std::size_t i = 0; i < mesh.node_count(); ++i)
    for (const geometry::Vec3& r : ring)
      if ((mesh.position_mm[i] - r).norm() <= distance_mm) {
        ep_node[i] = -1;
        break;
      }
}

}  // namespace systole::scene
