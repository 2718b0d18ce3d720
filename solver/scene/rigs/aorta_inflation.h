#pragma once
// The aorta alone, without blood, inflated quasi-statically: its compliance dV/dp around the
// ground pressure, the dry counterpart of the afterload that scenes fsi and fsei see
// (docs/notes/fsei-notebook.md), used by bench/structure/aorta_compliance and the tests.
//
// The aorta of the procedural heart with the scenes' options (tissue, structure.*, its Darcy
// outlet held as fsei.aorta.outlet_held holds it, which it requires; the root anchored to the
// valvular plane) carries a
// ground pressure p0 in one of the ways of fsei.aorta.pretension, generalised (ours):
//  - a share f of p0 by the wall's pre-stress: the springs' rest lengths from
//    structure::membrane_prestress at f p0, so the built shape is in equilibrium with f p0 inside;
//  - the rest, (1 - f) p0, by an outer follower load (the seed's "external force providing a
//    ground pressure", the scene's outer load).
// f = 1 is fsei.aorta.pretension = prestress, f = 0 the outer load. The blood's pressure p acts
// on the lumen as a follower load on every triangle outside the Darcy outlet (the loads of the
// pre-stress and of the outer load), so at p = p0 the built shape is (nearly: the pre-stress's
// smoothing leaves a residual) in equilibrium.
//
// Contract of hold(p, ...): ramps the inner pressure linearly from the current one to p over
// ramp_ms, then holds it until the lumen's volume changes by less than settle_ml over settle_window_ms
// (or max_ms has passed: settled = false). The volume change is exact for the fixed ends: the
// root's anchor ring and the outlet's nodes do not move, so the enclosed volume changes by the
// change of the wall's signed volume sum (1/6) a . (b x c) over its triangles.
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/structure/prestress.h"
#include "solver/structure/shell.h"

namespace systole::scene {

struct AortaInflationPoint {
  double pressure_mmhg = 0;        // the inner pressure held
  double volume_change_ml = 0;     // lumen volume minus the built shape's
  double max_strain = 0;           // largest and smallest edge strain (l - l0) / l
  double min_strain = 0;
  double max_displacement_mm = 0;  // largest node displacement from the built shape
  double time_ms = 0;              // the clock when it settled (or gave up)
  bool settled = false;
};

class AortaInflation {
 public:
  // Throws InputError for bad input (the fraction outside [0, 1], a ground pressure < 0, a
  // damping <= 0, an outlet not held, a pre-stress beyond the strain limit:
  // structure::membrane_prestress's message).
  AortaInflation(const config::Scenario& scenario, double ground_pressure_mmhg, double prestress_fraction,
                 double damping_per_ms);

  // See the contract above. Throws InstabilityError (structure: body, node, time) when the wall
  // fails (an edge beyond the strain limit).
  AortaInflationPoint hold(double pressure_mmhg, double ramp_ms = 10, double max_ms = 400, double settle_ml = 0.01,
                           double settle_window_ms = 5);

  double volume_change_ml() const;
  const structure::ShellModel& aorta() const { return aorta_; }
  const structure::Prestress& prestress() const { return prestress_; }

 private:
  void advance(double step_ms, double inner_pressure_mmhg);
  AortaInflationPoint sample() const;

  geometry::LeftHeart heart_;
  structure::ShellModel aorta_;
  structure::Prestress prestress_;
  double outer_kpa_ = 0;
  double pressure_mmhg_ = 0;  // the inner pressure now
  double signed_volume_built_mm3_ = 0;
};

}  // namespace systole::scene
