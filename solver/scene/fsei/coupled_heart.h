#pragma once
// The coupled scene's modules, assembled in the order each needs the last (MODEL.md §1–2): the
// grid of the resolution preset, the procedural heart in its box, the shells of its deformable
// bodies with the aorta's pre-tension, the immersed boundary's markers on them, the blood on
// slabs balanced by the markers, the direct forcing, and the chambers' active tension. Then
// CoupledStep (coupled_step.h) wires them into the seed's Fig. 6.
#include <filesystem>
#include <optional>

#include "solver/config/scenario.h"
#include "solver/core/state_archive.h"
#include "solver/coupling/fluid_module.h"
#include "solver/fluid/fluid.h"
#include "solver/geometry/left_heart.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/markers.h"
#include "solver/scene/fsei/bodies.h"
#include "solver/scene/fsei/scales.h"
#include "solver/scene/fsei/tension.h"
#include "solver/scene/fsei_scene.h"

namespace systole::scene::fsei {

// A checkpoint to resume from (checkpoint.h): its directory and its archive, or none.
struct Resume {
  std::optional<std::filesystem::path> directory;
  StateArchive state;
  const StateArchive* archive() const { return directory ? &state : nullptr; }
  double time_ms() const { return directory ? state.scalar("scene/time_ms") : 0.0; }
};

// The checkpoint of this scenario in control's checkpoint directory, if any (its fingerprint
// must match; the run's length, outputs and intervals may differ). Throws InputError for a
// checkpoint of another scenario or one past end_ms.
Resume find_resume_point(const config::Scenario& s, const std::filesystem::path& checkpoint_root, double end_ms);

class CoupledHeart {
 public:
  CoupledHeart(const config::Scenario& s, const Resume& resume);
  CoupledHeart(const CoupledHeart&) = delete;
  CoupledHeart& operator=(const CoupledHeart&) = delete;

  const config::Scenario& s;
  const GridPoints points;
  const grid::Grid grid;
  const geometry::LeftHeart heart;
  structure::BodyGroup group;               // the shells, in deformable_bodies() order
  const AortaPretension aorta;
  ibm::Markers markers;                     // the plane first, then links' bodies
  const std::vector<Link> links;
  const std::vector<double> marker_z_at_rest;  // grid units
  const grid::Slabs slabs;
  fluid::FluidSolver fluid;
  const double aorta_initial_ml;            // the blood started at the ground pressure (a note)
  const ibm::ForcingParameters forcing_parameters;
  ibm::DirectForcing forcing;
  coupling::FluidModule fluid_module;
  ChamberTension tension;
  const OutputScales scales;
};

}  // namespace systole::scene::fsei
