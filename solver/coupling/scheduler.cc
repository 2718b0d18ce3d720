#include "solver/coupling/scheduler.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>
#include <stdexcept>

#include "solver/core/errors.h"

namespace systole::coupling {
namespace {

std::string number(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

double norm(const std::vector<double>& v) {
  return std::sqrt(std::inner_product(v.begin(), v.end(), v.begin(), 0.0));
}

}  // namespace

void validate(const SchedulerOptions& o) {
  auto range = [](const char* field, double value, const char* allowed) {
    throw InputError(std::string("coupling option ") + field + " = " + number(value) + " is out of range " +
                     allowed);
  };
  if (!(o.sync_step_ms > 0) || !std::isfinite(o.sync_step_ms)) range("sync_step_ms", o.sync_step_ms, "(0, inf)");
  if (!(o.strong_tolerance > 0)) range("strong_tolerance", o.strong_tolerance, "(0, inf)");
  if (o.strong_max_iterations < 1) range("strong_max_iterations", o.strong_max_iterations, "[1, inf)");
  if (!(o.relaxation_factor > 0 && o.relaxation_factor <= 1))
    range("relaxation_factor", o.relaxation_factor, "(0, 1]");
  if (!(o.min_step_ms > 0)) range("min_step_ms", o.min_step_ms, "(0, inf)");
  if (!(o.step_limit_factor > 0) || !std::isfinite(o.step_limit_factor))
    range("step_limit_factor", o.step_limit_factor, "(0, inf)");
}

Scheduler::Scheduler(std::vector<Stage> stages, SchedulerOptions options)
    : stages_(std::move(stages)), options_(options) {
  validate(options_);
  if (stages_.empty()) throw std::invalid_argument("Scheduler: no stages");
  for (const Stage& s : stages_)
    if (s.module == nullptr) throw std::invalid_argument("Scheduler: a stage has no module");
  time_ms_ = stages_.front().module->time_ms();
  for (const Stage& s : stages_) {
    if (std::abs(s.module->time_ms() - time_ms_) > 1e-9 * std::max(1.0, std::abs(time_ms_)))
      throw std::invalid_argument("Scheduler: module '" + s.module->name() + "' starts at t = " +
                                  number(s.module->time_ms()) + " ms, module '" + stages_.front().module->name() +
                                  "' at " + number(time_ms_) + " ms");
    ModuleStats m;
    m.name = s.module->name();
    stats_.modules.push_back(m);
  }
  std::size_t transfers = 0;
  for (const Stage& s : stages_) transfers += s.after.size();
  current_.resize(transfers);
  previous_.resize(transfers);
  previous_residual_.resize(transfers);
  aitken_.assign(transfers, options_.relaxation_factor);
}

void Scheduler::sub_cycle(std::size_t stage, double t_end_ms) {
  Module& m = *stages_[stage].module;
  ModuleStats& st = stats_.modules[stage];
  const auto start = std::chrono::steady_clock::now();
  const double landing = 1e-12 * std::max(1.0, std::abs(t_end_ms));
  while (t_end_ms - m.time_ms() > landing) {
    const double left = t_end_ms - m.time_ms();
    const double limit = m.max_step_ms();
    if (!std::isfinite(limit) || limit < options_.min_step_ms)
      throw InstabilityError("coupling", "module " + m.name(), m.time_ms() / 1000,
                             "the stable step of module '" + m.name() + "' fell to " + number(limit) +
                                 " ms, below the floor min_step_ms = " + number(options_.min_step_ms) + " ms");
    // Split what is left of the interval evenly: no sliver of a last substep (ours).
    const double allowed = options_.step_limit_factor * limit;
    const double substeps = std::ceil(left / allowed * (1 - 1e-12));
    const double dt = substeps <= 1 ? left : left / substeps;
    m.step(dt);
    if (st.steps == 0) st.min_step_ms = st.max_step_ms = dt;
    st.min_step_ms = std::min(st.min_step_ms, dt);
    st.max_step_ms = std::max(st.max_step_ms, dt);
    st.max_step_over_limit = std::max(st.max_step_over_limit, dt / limit);
    ++st.steps;
  }
  st.wall_time_s += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// One pass over the stages (Gauss–Seidel: a transfer's data reach later stages in the same
// pass). iteration < 0: loose coupling, data written as read. iteration >= 0: strong coupling,
// pass number `iteration` of this interval; each transfer's raw data x̃_k is relaxed,
//   x_k = x_{k-1} + ω_k (x̃_k − x_{k-1})   (x_0 = x̃_0: the first pass is a loose step),
// ω constant, or Aitken's Δ² (Küttler & Wall 2008, Comput. Mech. 43:61) per transfer (ours),
// and x_k written. Returns max over transfers of |x̃_k − x_{k-1}| / |x̃_k| (0 for pass 0).
double Scheduler::run_pass(double t_end_ms, int iteration) {
  double worst = 0;
  std::size_t k = 0;
  for (std::size_t s = 0; s < stages_.size(); ++s) {
    sub_cycle(s, t_end_ms);
    for (const Transfer& tr : stages_[s].after) {
      std::vector<double>& raw = current_[k];
      tr.read(raw);
      if (iteration < 0) {
        tr.write(raw);
      } else {
        worst = std::max(worst, relax(k, tr.relaxed, iteration));
        tr.write(previous_[k]);
      }
      ++k;
    }
  }
  ++stats_.passes;
  return worst;
}

double Scheduler::relax(std::size_t k, bool relaxed_transfer, int iteration) {
  const std::vector<double>& raw = current_[k];
  std::vector<double>& x = previous_[k];
  std::vector<double>& last_residual = previous_residual_[k];
  if (iteration == 0 || x.size() != raw.size()) {
    const double change = iteration == 0 ? 0.0 : 1.0;  // data that changed size: not converged
    x = raw;
    last_residual.assign(raw.size(), 0.0);
    aitken_[k] = options_.relaxation_factor;
    return change;
  }
  std::vector<double> r(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) r[i] = raw[i] - x[i];
  const double change = norm(r) / std::max(norm(raw), 1e-300);
  double omega = 1;
  if (relaxed_transfer && options_.relaxation != Relaxation::none) {
    omega = options_.relaxation_factor;
    if (options_.relaxation == Relaxation::aitken && iteration >= 2) {
      double num = 0, den = 0;
      for (std::size_t i = 0; i < r.size(); ++i) {
        const double d = r[i] - last_residual[i];
        num += last_residual[i] * d;
        den += d * d;
      }
      omega = den > 0 ? -aitken_[k] * num / den : aitken_[k];
      if (!std::isfinite(omega) || omega == 0) omega = options_.relaxation_factor;
      omega = std::clamp(omega, -2.0, 2.0);  // (ours) keep a wild estimate bounded
    }
  }
  aitken_[k] = omega;
  for (std::size_t i = 0; i < raw.size(); ++i) x[i] += omega * r[i];
  last_residual = r;
  return change;
}

void Scheduler::export_state(StateArchive& a, const std::string& prefix) const {
  a.put_scalar(prefix + "time_ms", time_ms_);
  a.put(prefix + "counts", {static_cast<double>(stats_.intervals), static_cast<double>(stats_.passes),
                            static_cast<double>(stats_.unconverged_intervals), stats_.max_final_residual});
  std::vector<double> m;
  for (const ModuleStats& s : stats_.modules)
    m.insert(m.end(), {static_cast<double>(s.steps), s.min_step_ms, s.max_step_ms, s.max_step_over_limit, s.wall_time_s});
  a.put(prefix + "modules", m);
}

void Scheduler::import_state(const StateArchive& a, const std::string& prefix) {
  const double t = a.scalar(prefix + "time_ms");
  for (const Stage& s : stages_)
    if (std::abs(s.module->time_ms() - t) > 1e-9 * std::max(1.0, std::abs(t)))
      throw std::invalid_argument("Scheduler::import_state: module '" + s.module->name() + "' is at t = " +
                                  number(s.module->time_ms()) + " ms, the checkpoint at " + number(t) + " ms");
  const std::vector<double>& c = a.get(prefix + "counts", 4);
  const std::vector<double>& m = a.get(prefix + "modules", static_cast<long>(5 * stats_.modules.size()));
  time_ms_ = t;
  stats_.intervals = static_cast<long long>(c[0]);
  stats_.passes = static_cast<long long>(c[1]);
  stats_.unconverged_intervals = static_cast<long long>(c[2]);
  stats_.max_final_residual = c[3];
  for (std::size_t k = 0; k < stats_.modules.size(); ++k) {
    ModuleStats& s = stats_.modules[k];
    s.steps = static_cast<long long>(m[5 * k]);
    s.min_step_ms = m[5 * k + 1];
    s.max_step_ms = m[5 * k + 2];
    s.max_step_over_limit = m[5 * k + 3];
    s.wall_time_s = m[5 * k + 4];
  }
}

void Scheduler::advance_to(double t_ms) {
  if (!(t_ms >= time_ms_ - 1e-12 * std::max(1.0, std::abs(time_ms_))))
    throw std::invalid_argument("Scheduler::advance_to: t = " + number(t_ms) + " ms is before the current time " +
                                number(time_ms_) + " ms");
  const double landing = 1e-12 * std::max(1.0, std::abs(t_ms));
  while (t_ms - time_ms_ > landing) {
    const double left = t_ms - time_ms_;
    const double intervals = std::ceil(left / options_.sync_step_ms * (1 - 1e-12));
    const double t_end = intervals <= 1 ? t_ms : time_ms_ + options_.sync_step_ms;
    if (options_.mode == CouplingMode::loose) {
      run_pass(t_end, -1);
    } else {
      for (Stage& s : stages_) s.module->save();
      double residual = 0;
      bool converged = false;
      for (int it = 0; it < options_.strong_max_iterations; ++it) {
        if (it > 0)
          for (Stage& s : stages_) s.module->restore();
        residual = run_pass(t_end, it);
        if (it > 0 && residual < options_.strong_tolerance) {
          converged = true;
          break;
        }
      }
      if (!converged && options_.strong_max_iterations > 1) ++stats_.unconverged_intervals;
      if (options_.strong_max_iterations > 1) stats_.max_final_residual = std::max(stats_.max_final_residual, residual);
    }
    time_ms_ = t_end;
    ++stats_.intervals;
  }
}

}  // namespace systole::coupling
