#pragma once
// The left heart's electrophysiology as the scenario sets it up: a helper shared by the scenes
// that run EP on the procedural (or an imported) heart (electro, electromechanics, fsei), so no
// scene includes another's header. Contract: builds the EP mesh, tissue options and probes from
// the scenario and the given bodies; touches no state and does no time stepping.
#include <cstddef>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/tri_mesh.h"

namespace systole::scene {

// The LV (domain 0) and LA (domain 1) myocardial walls of the given bodies
// (electro::from_surfaces, source_node filled), the cell models per domain, the seed's stimuli
// (Bachmann bundle at t = 0, His bundle at av_delay_ms, the Purkinje surrogate sites), every
// period, and the named probe nodes (his_bundle, lv_apex, bachmann_bundle where tagged).
struct EpProbe {
  std::string name;
  std::size_t node;
};
struct LeftHeartEp {
  electro::ElectroMesh mesh;
  electro::TissueOptions options;
  std::vector<EpProbe> probes;
  int lv_domain = 0, la_domain = 1;  // mesh domain of each chamber; -1 if absent (heart_ep)
};
LeftHeartEp left_heart_ep(const config::Scenario& scenario, const geometry::TriMesh& lv,
                          const geometry::TriMesh& la);
// The same for a heart that may lack one chamber (an imported LV alone or LA alone): a null
// body is left out, the other chamber becomes domain 0 (lv_domain / la_domain say which); at
// least one body must be given (InputError otherwise). left_heart_ep(s, lv, la) is
// heart_ep(s, &lv, &la).
LeftHeartEp heart_ep(const config::Scenario& scenario, const geometry::TriMesh* lv, const geometry::TriMesh* la);

// The tissue options every EP scene takes from the scenario (formulation, splitting, time step,
// chi, C_m, conductivities, activation threshold, the tension's k and time scale, threads),
// with the given cell models (one per domain) and stimuli. left_heart_ep uses it; scene
// "electro" too, for its sheet and slab.
electro::TissueOptions ep_tissue_options(const config::Scenario& scenario, std::vector<std::string> models,
                                         std::vector<electro::StimulusSpec> stimuli);

}  // namespace systole::scene
