#include "solver/scene/fsei/valve_switches.h"

#include <cmath>
#include <sstream>

#include "solver/scene/fsei_scene.h"

namespace systole::scene::fsei {

using geometry::Vec3;

ValveSwitches::ValveSwitches(CoupledHeart& h)
    : h_(h), period_ms_(h.s.period_ms()), limiter_on_(h.s.structure.mitral_limiter) {}

void ValveSwitches::apply(double t_ms) {
  set_caps(t_ms);
  set_mitral_limiter(t_ms);
}

std::vector<double> ValveSwitches::switch_times_after(double t_ms) const {
  const double beat0 = std::floor(t_ms / period_ms_ + 1e-9) * period_ms_;
  return {beat0 + period_ms_ - h_.s.av_delay_ms, beat0 + period_ms_,
          beat0 + h_.s.structure.mitral_limiter_end_phase * period_ms_};
}

bool ValveSwitches::caps_closed(double t_ms) const {  // from the LA stimulus to the next LV stimulus
  const double phase = std::fmod(t_ms, period_ms_);
  return phase >= period_ms_ - h_.s.av_delay_ms - 1e-9;
}

void ValveSwitches::set_caps(double t_ms) {
  for (const Link& l : h_.links)
    if (l.cap && h_.markers.bodies()[static_cast<std::size_t>(l.marker_body)].active != caps_closed(t_ms)) {
      h_.markers.set_active(l.marker_body, caps_closed(t_ms));
      h_.forcing.markers_moved();
    }
}

void ValveSwitches::set_mitral_limiter(double t_ms) {
  const config::Structure& st = h_.s.structure;
  if (!st.mitral_limiter || mitral_limiter_holds(t_ms, period_ms_, st.mitral_limiter_end_phase) == limiter_on_) return;
  limiter_on_ = !limiter_on_;
  for (std::string_view name : {geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody}) {
    structure::ShellModel& leaflet = h_.group.body(shell_index(name));
    if (!limiter_on_) {
      leaflet.clear_displacement_limit();
      continue;
    }
    const std::vector<Vec3>& x = leaflet.positions_mm();
    const std::vector<Vec3>& x0 = h_.heart.body(name).position_mm;  // the built, closed valve
    for (std::size_t i = 0; i < x.size(); ++i) {
      const double beyond = (x0[i] - x[i]).z() - st.mitral_limit_mm;  // towards the LA, -z
      if (beyond > worst_mm_)
        worst_mm_ = beyond, worst_t_ms_ = t_ms, worst_node_ = std::string(name) + "' node " + std::to_string(i);
    }
    leaflet.set_displacement_limit(-Vec3::UnitZ(), st.mitral_limit_mm, x0);
  }
  if (limiter_on_) ++engagements_;
}

std::string ValveSwitches::limiter_note() const {
  const config::Structure& st = h_.s.structure;
  if (!(st.mitral_limiter && st.mitral_limiter_end_phase < 1)) return {};
  std::ostringstream m;
  m << "the mitral limiter held over t/T in [0, " << st.mitral_limiter_end_phase << ") of every beat; engaged "
    << engagements_ << " time(s) at a beat's start in this run";
  if (worst_mm_ > 0)
    m << ", the farthest node beyond its limit at an engagement: body '" << worst_node_ << " by " << worst_mm_
      << " mm at t = " << worst_t_ms_ << " ms (projected back in one step)";
  return m.str();
}

}  // namespace systole::scene::fsei
