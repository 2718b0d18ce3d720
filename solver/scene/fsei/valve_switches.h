#pragma once
// What the scene switches at fixed phases of every beat (MODEL.md §1–2): the pulmonary-vein caps
// closed from the LA stimulus to the next LV stimulus (the atrial contraction), and the mitral
// limiter (the seed's stand-in for the chordae) over the phases [0,
// structure.mitral_limiter_end_phase). The scene's intervals are clipped at these times.
#include <string>
#include <vector>

#include "solver/scene/fsei/coupled_heart.h"

namespace systole::scene::fsei {

class ValveSwitches {
 public:
  explicit ValveSwitches(CoupledHeart& h);
  // Sets the caps and the limiter for time t_ms.
  void apply(double t_ms);
  // The switch times after t_ms within its beat and at the next beat's start.
  std::vector<double> switch_times_after(double t_ms) const;
  // A note on the limiter's engagements (empty when it holds all the time or is off).
  std::string limiter_note() const;

 private:
  void set_caps(double t_ms);
  void set_mitral_limiter(double t_ms);
  bool caps_closed(double t_ms) const;

  CoupledHeart& h_;
  const double period_ms_;
  bool limiter_on_;
  // Engaging the limiter projects every leaflet node back within the limit in the next structure
  // step, a kinematic jump (ours): how far beyond it a node was is reported.
  double worst_mm_ = 0, worst_t_ms_ = 0;
  std::string worst_node_;
  int engagements_ = 0;
};

}  // namespace systole::scene::fsei
