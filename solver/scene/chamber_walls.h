#pragma once
// The LV and LA walls as scenes "electromechanics", "fsi" and "fsei" build them (calibrated in
// docs/electromechanics.md): the tissue with the electromechanics section's passive scale and
// isotropy, the walls' shell options, and the fibrous annulus that carries no active tension.
#include <cstdint>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/structure/contact.h"
#include "solver/structure/shell.h"

namespace systole::scene {

// tissue.* with the LV and LA Fung c × electromechanics.passive_stiffness_scale and, when
// electromechanics.isotropic_passive, alpha_c = alpha_f (ours).
structure::ShellMaterials chamber_wall_materials(const config::Scenario& scenario);

// structure.* options with the walls' law and bending from the electromechanics section, the
// tissue's active options, and the cavity closed by the plane at plane_z_mm.
structure::ShellOptions chamber_wall_options(const config::Scenario& scenario, double plane_z_mm);

// The structure.* options for the other bodies (leaflets, aorta), cavity closed at plane_z_mm.
structure::ShellOptions structure_options(const config::Scenario& scenario, double plane_z_mm);

// The contact between the bodies from structure.* (contact, contact_rule, contact_distance_mm,
// contact_stiffness_kpa_per_mm, contact_damping_ratio), the Verlet skin half the layer.
structure::ContactOptions contact_options(const config::Scenario& scenario);

// The shell of one heart body: built on its stress-free shape (geometry::rest_shape) and, when the
// mesh was built in another shape (the mitral leaflets with geometry.mitral_rest_opening_mm > 0),
// started at rest at the built positions (pre-strained, ours). Throws what ShellModel throws, and
// InputError when the built shape's largest edge strain from the rest shape is not below
// options.strain_limit (the run would stop at its first step).
structure::ShellModel body_shell(const geometry::TriMesh& built, const structure::ShellMaterials& materials,
                                 const structure::ShellOptions& options);

// Sets ep_node[i] = -1 (no active tension) for the nodes within distance_mm (stress-free
// positions) of the mesh's anchor ring: the fibrous annulus is not muscle (ours). No-op for
// distance_mm <= 0.
void clear_passive_annulus(const geometry::TriMesh& mesh, double distance_mm, std::vector<std::int32_t>& ep_node);

}  // namespace systole::scene
