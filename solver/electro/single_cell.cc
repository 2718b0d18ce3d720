#include "solver/electro/single_cell.h"

#include <cmath>
#include <limits>

#include "solver/core/errors.h"
#include "solver/electro/ionic/cell_model.h"

namespace systole::electro {

ApBiomarkers pace_single_cell(const std::string& name, const PacingProtocol& pr) { return pace_single_cell(name, pr, {}); }

ApBiomarkers pace_single_cell(const std::string& name, const PacingProtocol& pr,
                              const std::vector<std::pair<std::string, double>>& parameters) {
  auto model = ionic::make_cell_model(name, 1);
  for (const auto& [p, value] : parameters) model->set_parameter(p, value);
  if (pr.dt_ms > model->max_stable_dt_ms())
    throw InputError("single cell: dt_ms = " + std::to_string(pr.dt_ms) + " exceeds the largest stable step of '" +
                     name + "' (" + std::to_string(model->max_stable_dt_ms()) + " ms)");
  const long steps_per_beat = std::lround(pr.period_ms / pr.dt_ms);
  double v = model->resting_potential_mv(), iion = 0;
  ApBiomarkers out{};
  for (int beat = 0; beat < pr.beats; ++beat) {
    const bool last = beat + 1 == pr.beats;
    if (last) {
      out.rest_mv = v;
      out.last_beat_vm_mv.reserve(static_cast<std::size_t>(steps_per_beat));
    }
    for (long s = 0; s < steps_per_beat; ++s) {
      const double t = s * pr.dt_ms;
      const double stim = (t + 0.5 * pr.dt_ms) < pr.stimulus_ms ? pr.stimulus_ua_per_uf : 0.0;
      model->compute({0, 1}, pr.dt_ms, &v, &iion);
      v += pr.dt_ms * (stim - iion);
      if (!std::isfinite(v)) throw InstabilityError("electro", "single cell " + name, beat * pr.period_ms * 1e-3, "Vm not finite");
      if (last) out.last_beat_vm_mv.push_back(v);
    }
  }
  const auto& tr = out.last_beat_vm_mv;
  out.peak_mv = -std::numeric_limits<double>::infinity();
  out.dvdt_max_v_per_s = 0;
  double prev = out.rest_mv, t_up = 0;
  for (std::size_t k = 0; k < tr.size(); ++k) {
    out.peak_mv = std::max(out.peak_mv, tr[k]);
    const double d = (tr[k] - prev) / pr.dt_ms;
    if (d > out.dvdt_max_v_per_s) {
      out.dvdt_max_v_per_s = d;
      t_up = (static_cast<double>(k) + 0.5) * pr.dt_ms;
    }
    prev = tr[k];
  }
  auto crossing = [&](double fraction) {
    const double level = out.rest_mv + fraction * (out.peak_mv - out.rest_mv);
    std::size_t k = 0;
    while (k < tr.size() && tr[k] < out.peak_mv) ++k;
    for (; k + 1 < tr.size(); ++k)
      if (tr[k] > level && tr[k + 1] <= level) {
        const double tk = (static_cast<double>(k) + 1.0) * pr.dt_ms;
        return tk + pr.dt_ms * (tr[k] - level) / (tr[k] - tr[k + 1]) - t_up;
      }
    return std::numeric_limits<double>::quiet_NaN();
  };
  out.apd50_ms = crossing(0.5);
  out.apd90_ms = crossing(0.1);
  return out;
}

}  // namespace systole::electro
