#pragma once
// Where the coupled scene reads the blood (ours): chamber pressures as spatial means over probe
// spheres, flows through the valves' orifice disks, and Doppler-like sample volumes at the
// leaflets' tips. All collective over the fluid's slabs; results nondimensional.
#include <array>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/fluid/fluid.h"
#include "solver/geometry/left_heart.h"

namespace systole::scene::fsei {

// A sphere of cells whose mean pressure is a chamber's pressure.
struct Probe {
  std::string name;
  geometry::Vec3 centre_mm;
};

// The scene's probes, in this order: the LV at 40 % of the long axis below the plane, the LA at
// its nodes' centroid, the aortic root 8 mm above the aortic orifice, the outer reference in a
// box corner, the descending aorta one outflow radius upstream of the Darcy region (the root's
// probe sits in the ejection's jet, whose dynamic pressure it does not see).
enum ProbeIndex : std::size_t { kProbeLv, kProbeLa, kProbeAorticRoot, kProbeOuter, kProbeDescendingAorta };
std::vector<Probe> chamber_probes(const config::Scenario& s, const geometry::LeftHeart& heart);

// Mean pressure over the cells whose centres lie within radius_mm of each probe. Throws
// InputError naming fsei.probe_radius_mm when a probe holds no cell centre.
std::vector<double> probe_pressures(const fluid::FluidSolver& fluid, const std::vector<Probe>& probes, double radius_mm);

// Volume flux (+ along +z) through the disk of radius_mm around centre_mm on the z-face plane
// nearest to its z.
double disk_flux(const fluid::FluidSolver& fluid, const geometry::Vec3& centre_mm, double radius_mm);

// Mean z-velocity over that disk (one face layer); 0 when the disk holds no face.
double disk_mean_w(const fluid::FluidSolver& fluid, const geometry::Vec3& centre_mm, double radius_mm);

}  // namespace systole::scene::fsei
