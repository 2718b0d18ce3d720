#pragma once
// The blood of the coupled scene (MODEL.md §2): the fluid box on slabs split by the planes'
// work, the Darcy afterload around the end of the descending aorta, the aorta's blood at the
// ground pressure at t = 0, and the direct forcing that carries the markers' no-slip condition
// into the fluid (eq 1–10).
#include <vector>

#include "solver/config/scenario.h"
#include "solver/fluid/fluid.h"
#include "solver/geometry/left_heart.h"
#include "solver/grid/grid.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/markers.h"

namespace systole::scene::fsei {

// The z of every marker (grid units): the slabs' weights and the ranks' note.
std::vector<double> marker_z(const ibm::Markers& markers);

// The fluid's slabs on MPI_COMM_WORLD (fsei.slab_split: "balanced" weighs each z plane by its
// cells plus its share of the markers, slab_plane_weights; "uniform": equal blocks).
grid::Slabs fluid_slabs(const config::Scenario& s, const grid::Grid& g, const std::vector<double>& marker_z);

// The fluid's parameters: the seed's Reynolds number for fluid.kinematic_viscosity_m2_per_s, the
// step at fluid.cfl capped by the synchronisation step, the blow-up bound on the step (ours) and
// the Darcy region around the descending aorta's outflow cylinder.
fluid::FluidParameters fluid_parameters(const config::Scenario& s, const geometry::LeftHeart& heart);

// The blood inside the aorta at fsei.aorta.ground_pressure_mmhg above the rest of the box at t = 0
// (the seed's pre-tension, when it is not ramped; ours in detail: an AortaInterior test per
// cell). Collective. Returns the volume started at it in ml (0 when none).
double start_aorta_at_ground_pressure(const config::Scenario& s, const geometry::LeftHeart& heart,
                                      const grid::Grid& g, fluid::FluidSolver& fluid);

// The direct forcing's parameters from fsei.forcing (kernel, passes, carry-over and its
// exclusion rings; the valvular plane is the one rigid body). The carry-over's increment share is
// set per step from fsei.forcing.carry_over_reference_cfl (coupling::FluidModuleOptions).
ibm::ForcingParameters forcing_parameters(const config::Fsei::Forcing& forcing);

}  // namespace systole::scene::fsei
