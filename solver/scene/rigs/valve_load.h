#pragma once
// The closed valves alone, without blood, under a uniform pressure difference: does the valve
// carry the load, how far does it sag and how much do its edges strain? The dry counterpart of
// the first milliseconds of scenes fsi and fsei (docs/fsei.md, "The closed valves"), used by
// bench/structure/valve_load and the tests.
// Aortic: the three cusps of the procedural heart loaded from the aorta's side; mitral: the two
// leaflets loaded from the LV's side with the scenario's limiter. The bodies are those of the
// scenes (geometry, tissue, structure.* options, contact), with the damping given here.
#include <string_view>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"
#include "solver/structure/contact.h"

namespace systole::scene {

enum class Valve { kAortic, kMitral };

struct ValveLoadSample {
  double t_ms = 0;
  double pressure_mmhg = 0;        // the pressure difference applied during the last advance
  double max_displacement_mm = 0;  // largest node displacement from the built shape
  double max_strain = 0;           // largest and smallest edge strain (l - l0) / l
  double min_strain = 0;
  int contact_pairs = 0;           // active node-surface contact pairs
  double max_speed_m_s = 0;        // the fastest node's speed (a valve at rest under its load: ~0)
  double stable_step_ms = 0;       // the group's stable substep
};

class ClosedValveLoad {
 public:
  // Builds the heart of `scenario` and the valve's bodies. Throws InputError for bad input.
  ClosedValveLoad(const config::Scenario& scenario, Valve valve, double damping_per_ms);

  // Advances by step_ms (> 0) with the pressure difference pressure_mmhg pushing the closed
  // valve towards the LV (aortic) or the LA (mitral) when positive, and opening it (from the
  // aorta's / the LA's side higher to the other) when negative. Throws InstabilityError, naming
  // the body, node and time, when the valve fails (an edge beyond the strain limit, a stable
  // step below the minimum); the state is then that of the failure.
  ValveLoadSample advance(double step_ms, double pressure_mmhg);

  // Mitral only: the distance (mm) between the two leaflets' free edges at their middles, the
  // mean x of each leaflet's nodes within 3 mm of its deepest built z (its free edge's middle
  // third; the built valve: valve_gap_mm apart, the leaflets facing each other across x). The
  // opening's measure of docs/notes/fsei-notebook.md. Throws std::logic_error for the aortic
  // valve.
  double mitral_free_edge_gap_mm() const;

  double time_ms() const { return t_ms_; }
  const geometry::LeftHeart& heart() const { return heart_; }
  const structure::BodyGroup& group() const { return group_; }
  const std::vector<std::string_view>& body_names() const { return names_; }

 private:
  ValveLoadSample sample(double pressure_mmhg) const;

  Valve valve_;
  geometry::LeftHeart heart_;
  std::vector<std::string_view> names_;
  structure::BodyGroup group_;
  double t_ms_ = 0;
};

}  // namespace systole::scene
