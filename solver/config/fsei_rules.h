#pragma once
// Scenes "fsi" and "fsei" (solver/scene/fsei_scene.h): their fluid grid, and every cross-field
// rule of theirs that depends only on the scenario. parse_scenario() runs the rules, so a bad
// fsi/fsei scenario is refused when it is parsed (at submit), never on a worker.
#include <string>
#include <vector>

#include "solver/config/scenario.h"

namespace systole::config {

// The grid points (nx, ny, nz) of a resolution preset (in z following fluid.box_z_mm at the
// preset's spacing); "custom" takes fluid.nx/ny/nz.
// Throws InputError naming fsei.resolution for an unknown name.
struct GridPoints {
  int nx = 0, ny = 0, nz = 0;
};
GridPoints fsei_grid_points(const Scenario& scenario);

// The coarsest grid the valves allow (ours): the aortic orifice (geometry.aortic_diameter_mm)
// must span this many cells of the grid's largest spacing, or the closed cusps and the open
// orifice are not told apart.
inline constexpr double kMinCellsAcrossAorticOrifice = 8;

// Appends one message per violated rule of scenes fsi/fsei to `errors`, each naming the fields,
// their values and what is allowed: the aorta's pre-stress share, the coupling's order,
// first-pass predictor and steps per interval, the mitral limiter's window, the grid against the
// aortic orifice and the pressure probes, and for scene fsei the EP's step and mesh. Every field
// must already be in its range (parse_scenario() calls this after the field checks).
void check_fsei_rules(const Scenario& scenario, std::vector<std::string>& errors);

}  // namespace systole::config
