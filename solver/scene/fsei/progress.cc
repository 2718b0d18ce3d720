#include "solver/scene/fsei/progress.h"

#include <cmath>
#include <sstream>

namespace systole::scene::fsei {
namespace {

using geometry::Vec3;

// What sets the fluid's step (CFL bound: the three largest speeds, each over its own faces), the
// fastest node of the shells (mm/ms = m/s: a body moving fast drags its blood) and the largest
// carried-over force (the forcing's integral state, m/s²: what winds up where the slip cannot be
// removed), its body, place and whether it carries.
void step_limits(const CoupledHeart& h, std::ostream& m) {
  const fluid::FluidParameters& fp = h.fluid.parameters();
  const double m_s = 1e-3 * fp.length_scale_mm / fp.time_scale_s;
  const std::array<double, 3> u = h.fluid.max_velocity();
  m << " fluid_dt_ms " << 1e3 * fp.time_scale_s * h.fluid.last_dt() << " max_uvw_m_s " << u[0] * m_s << " " << u[1] * m_s
    << " " << u[2] * m_s << " fastest " << h.fluid.fastest_cell();
  double v_max = 0;
  std::string v_body = "-";
  for (std::size_t b = 0; b < h.group.body_count(); ++b)
    for (const Vec3& v : h.group.body(b).velocities_mm_per_ms())
      if (v.norm() > v_max) v_max = v.norm(), v_body = h.group.body(b).name();
  m << " fastest_node_m_s " << v_max << " in " << v_body;
  const std::vector<Vec3>& carried = h.forcing.carried_force();
  if (carried.empty()) return;
  std::size_t b_max = 0;
  double f_max = -1;
  for (std::size_t b = 0; b < carried.size(); ++b)
    if (carried[b].squaredNorm() > f_max) f_max = carried[b].squaredNorm(), b_max = b;
  const ibm::MarkerArrays& ma = h.markers.markers();
  const Vec3 x_mm = ma.position[b_max] * fp.length_scale_mm;
  m << " carried_force_max_m_s2 " << std::sqrt(f_max) * m_s / fp.time_scale_s << " in "
    << h.markers.bodies()[static_cast<std::size_t>(ma.body[b_max])].name << " at (" << x_mm.x() << ", " << x_mm.y()
    << ", " << x_mm.z() << ") mm " << (h.forcing.carries_over(b_max) ? "carrying" : "excluded");
}

}  // namespace

ProgressReport progress_report(const CoupledHeart& h, const CoupledStep& step, const SeriesRecorder& series,
                               double t_ms, double end_ms) {
  const double period_ms = h.s.period_ms();
  ProgressReport rep;
  rep.simulated_time_s = 1e-3 * t_ms;
  rep.beat = 1 + static_cast<int>(t_ms / period_ms);
  rep.beats_total = static_cast<int>(std::ceil(end_ms / period_ms - 1e-9));
  rep.fraction = t_ms / end_ms;
  std::ostringstream m;
  m.precision(7);
  m << h.s.scene << " t_ms " << t_ms << series.progress_fields() << " mean_speed_m_s " << series.mean_speed_m_s();
  step_limits(h, m);
  if (h.s.fsei.strong_coupling) {  // how the iterations fare so far (a run that stops reports no metrics)
    const coupling::SchedulerStats& cs = step.stats();
    m << " passes " << cs.passes << " unconverged " << cs.unconverged_intervals << " of " << cs.intervals
      << " intervals, largest final residual " << cs.max_final_residual;
  }
  rep.message = m.str();
  return rep;
}

}  // namespace systole::scene::fsei
