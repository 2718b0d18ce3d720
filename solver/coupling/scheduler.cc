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
  if (o.iqn_reuse_intervals < 0) range("iqn_reuse_intervals", o.iqn_reuse_intervals, "[0, inf)");
  if (!(o.iqn_filter > 0 && o.iqn_filter < 1)) range("iqn_filter", o.iqn_filter, "(0, 1)");
  if (o.interval_stage < -1) range("interval_stage", o.interval_stage, "-1 (fixed intervals) or a stage index");
  if (o.interval_stage_steps < 1) range("interval_stage_steps", o.interval_stage_steps, "[1, inf)");
  if (!(o.min_step_ms > 0)) range("min_step_ms", o.min_step_ms, "(0, inf)");
  if (!(o.step_limit_factor > 0) || !std::isfinite(o.step_limit_factor))
    range("step_limit_factor", o.step_limit_factor, "(0, inf)");
  if (o.first_pass_predictor == FirstPassPredictor::linear && !(o.mode == CouplingMode::strong && o.first_pass_residual))
    throw InputError("coupling option first_pass_predictor = linear needs strong coupling with first_pass_residual "
                     "(the relaxed transfers consumed before they are produced in a pass)");
}

Scheduler::Scheduler(std::vector<Stage> stages, SchedulerOptions options)
    : stages_(std::move(stages)), options_(options) {
  validate(options_);
  if (stages_.empty()) throw std::invalid_argument("Scheduler: no stages");
  for (const Stage& s : stages_)
    if (s.module == nullptr) throw std::invalid_argument("Scheduler: a stage has no module");
  if (options_.interval_stage >= static_cast<int>(stages_.size()))
    throw InputError("coupling option interval_stage = " + std::to_string(options_.interval_stage) +
                     " is out of range: there are " + std::to_string(stages_.size()) + " stages (or -1: fixed intervals)");
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
  iqn_.resize(transfers);
  written_before_.resize(transfers);
}

void Scheduler::sub_cycle(std::size_t stage, double t_end_ms) {
  Module& m = *stages_[stage].module;
  ModuleStats& st = stats_.modules[stage];
  const auto start = std::chrono::steady_clock::now();
  const double landing = 1e-12 * std::max(1.0, std::abs(t_end_ms));
  while (t_end_ms - m.time_ms() > landing) {
    const double left = t_end_ms - m.time_ms();
    const double limit = m.max_step_ms();
    if (!std::isfinite(limit) || limit < options_.min_step_ms) {
      const std::string limiter = m.step_limiter();
      throw InstabilityError("coupling", "module " + m.name() + (limiter.empty() ? "" : ", " + limiter),
                             m.time_ms() / 1000,
                             "the stable step of module '" + m.name() + "' fell to " + number(limit) +
                                 " ms, below the floor min_step_ms = " + number(options_.min_step_ms) + " ms");
    }
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
// or IQN-ILS (below), and x_k written. Returns max over transfers of |x̃_k − x_{k-1}| / |x̃_k| (0 for pass 0).
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
    // data that changed size (or none written yet) are not converged; the first pass measures
    // nothing unless first_pass_residual asks it to, for the relaxed transfers
    double change = iteration == 0 ? 0.0 : 1.0;
    if (iteration == 0 && relaxed_transfer && options_.first_pass_residual) {
      if (x.size() != raw.size()) {
        change = 1.0;
      } else {
        double d2 = 0;
        for (std::size_t i = 0; i < raw.size(); ++i) d2 += (raw[i] - x[i]) * (raw[i] - x[i]);
        change = std::sqrt(d2) / std::max(norm(raw), 1e-300);
      }
    }
    QuasiNewtonMemory& m = iqn_[k];
    if (x.size() != raw.size() && !x.empty()) {
      m = QuasiNewtonMemory{};  // columns of another length are of no use
    } else if (iteration == 0 && !m.current.residual_differences.empty()) {
      if (options_.iqn_reuse_intervals > 0) m.earlier.insert(m.earlier.begin(), std::move(m.current));
      if (m.earlier.size() > static_cast<std::size_t>(options_.iqn_reuse_intervals))
        m.earlier.resize(static_cast<std::size_t>(options_.iqn_reuse_intervals));
      m.current = SecantColumns{};
    }
    x = raw;
    last_residual.assign(raw.size(), 0.0);
    aitken_[k] = options_.relaxation_factor;
    return change;
  }
  std::vector<double> r(raw.size());
  for (std::size_t i = 0; i < raw.size(); ++i) r[i] = raw[i] - x[i];
  const double change = norm(r) / std::max(norm(raw), 1e-300);
  if (relaxed_transfer && options_.relaxation == Relaxation::iqn_ils) {
    quasi_newton(k, raw, r, iteration);
    last_residual = r;
    return change;
  }
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

void Scheduler::predict(double interval_ms) {
  std::size_t k = 0;
  for (const Stage& s : stages_)
    for (const Transfer& tr : s.after) {
      std::vector<double>& x = previous_[k];  // x_n: the data last written
      std::vector<double>& before = written_before_[k];
      if (tr.relaxed && !x.empty()) {
        if (before.size() == x.size() && last_interval_ms_ > 0) {
          const double ratio = interval_ms / last_interval_ms_;
          std::vector<double> guess(x.size());
          for (std::size_t i = 0; i < x.size(); ++i) guess[i] = x[i] + ratio * (x[i] - before[i]);
          before = x;
          x = std::move(guess);
          tr.write(x);
        } else {
          before = x;  // one interval's data: the guess stays x_n this time
        }
      }
      ++k;
    }
}

// IQN-ILS (Degroote, Bathe & Vierendeels 2009, Comput. Struct. 87:793), with the columns of
// earlier intervals reused: the fixed-point map x -> x̃ = H(x) has residual r = x̃ − x. From
// passes i, i+1 the secant pairs Δr = r_{i+1} − r_i, Δx̃ = x̃_{i+1} − x̃_i form the columns of
// V and W (this interval's newest first, then earlier intervals'). The least-squares
// c = argmin |V c + r_k| predicts the r = 0 point, and
//   x_{k+1} = x̃_k + W c;
// without any column, x_{k+1} = x_k + ω r_k (ω = relaxation_factor). V is orthogonalised by
// modified Gram–Schmidt in that order, dropping a column whose part orthogonal to the kept
// ones is below iqn_filter times its norm (nearly dependent: it would make c wild). All ranks
// hold the same data, so all compute the same update.
void Scheduler::quasi_newton(std::size_t k, const std::vector<double>& raw, const std::vector<double>& r,
                             int iteration) {
  QuasiNewtonMemory& m = iqn_[k];
  std::vector<double>& x = previous_[k];
  const std::size_t n = raw.size();
  if (iteration >= 2 && m.last_raw.size() == n) {
    std::vector<double> dr(n), dx(n);
    for (std::size_t i = 0; i < n; ++i) {
      dr[i] = r[i] - previous_residual_[k][i];
      dx[i] = raw[i] - m.last_raw[i];
    }
    m.current.residual_differences.insert(m.current.residual_differences.begin(), std::move(dr));
    m.current.raw_differences.insert(m.current.raw_differences.begin(), std::move(dx));
  }
  m.last_raw = raw;
  // Q R = V (kept columns), with the matching columns of W
  std::vector<std::vector<double>> q;
  std::vector<std::vector<double>> r_columns;  // column j of R: j + 1 entries
  std::vector<const std::vector<double>*> w;
  auto offer = [&](const std::vector<double>& v, const std::vector<double>& wv) {
    const double v_norm = norm(v);
    if (!(v_norm > 0) || !std::isfinite(v_norm)) return;
    std::vector<double> u = v;
    std::vector<double> rc(q.size() + 1);
    for (std::size_t j = 0; j < q.size(); ++j) {
      rc[j] = std::inner_product(q[j].begin(), q[j].end(), u.begin(), 0.0);
      for (std::size_t i = 0; i < n; ++i) u[i] -= rc[j] * q[j][i];
    }
    const double u_norm = norm(u);
    if (u_norm < options_.iqn_filter * v_norm) return;
    for (double& e : u) e /= u_norm;
    rc.back() = u_norm;
    q.push_back(std::move(u));
    r_columns.push_back(std::move(rc));
    w.push_back(&wv);
  };
  for (std::size_t j = 0; j < m.current.residual_differences.size() && q.size() < n; ++j)
    offer(m.current.residual_differences[j], m.current.raw_differences[j]);
  for (const SecantColumns& e : m.earlier)
    for (std::size_t j = 0; j < e.residual_differences.size() && q.size() < n; ++j)
      offer(e.residual_differences[j], e.raw_differences[j]);
  if (q.empty()) {
    for (std::size_t i = 0; i < n; ++i) x[i] += options_.relaxation_factor * r[i];
    return;
  }
  // R c = −Qᵀ r by back substitution
  const std::size_t cols = q.size();
  std::vector<double> c(cols);
  for (std::size_t j = 0; j < cols; ++j) c[j] = -std::inner_product(q[j].begin(), q[j].end(), r.begin(), 0.0);
  for (std::size_t j = cols; j-- > 0;) {
    for (std::size_t l = j + 1; l < cols; ++l) c[j] -= r_columns[l][j] * c[l];
    c[j] /= r_columns[j][j];
  }
  x = raw;
  for (std::size_t j = 0; j < cols; ++j)
    for (std::size_t i = 0; i < n; ++i) x[i] += c[j] * (*w[j])[i];
}

void Scheduler::export_state(StateArchive& a, const std::string& prefix) const {
  a.put_scalar(prefix + "time_ms", time_ms_);
  a.put(prefix + "counts", {static_cast<double>(stats_.intervals), static_cast<double>(stats_.passes),
                            static_cast<double>(stats_.unconverged_intervals), stats_.max_final_residual});
  std::vector<double> m;
  for (const ModuleStats& s : stats_.modules)
    m.insert(m.end(), {static_cast<double>(s.steps), s.min_step_ms, s.max_step_ms, s.max_step_over_limit, s.wall_time_s});
  a.put(prefix + "modules", m);
  // first_pass_residual: the relaxed transfers' last written data (the next interval's first
  // pass is measured against them, and import_state writes them again)
  if (options_.first_pass_residual) {
    std::size_t k = 0;
    for (const Stage& s : stages_)
      for (const Transfer& tr : s.after) {
        if (tr.relaxed && !previous_[k].empty()) a.put(prefix + "written/" + std::to_string(k), previous_[k]);
        if (tr.relaxed && !written_before_[k].empty())
          a.put(prefix + "written_before/" + std::to_string(k), written_before_[k]);
        ++k;
      }
    if (options_.first_pass_predictor == FirstPassPredictor::linear)
      a.put_scalar(prefix + "last_interval_ms", last_interval_ms_);
  }
  // IQN-ILS's secant columns (the next interval reuses them): per transfer, the column count of
  // each interval (newest first) and the columns concatenated
  for (std::size_t k = 0; k < iqn_.size(); ++k) {
    const QuasiNewtonMemory& q = iqn_[k];
    std::vector<double> counts, dr, dx;
    auto add = [&](const SecantColumns& e) {
      counts.push_back(static_cast<double>(e.residual_differences.size()));
      for (std::size_t j = 0; j < e.residual_differences.size(); ++j) {
        dr.insert(dr.end(), e.residual_differences[j].begin(), e.residual_differences[j].end());
        dx.insert(dx.end(), e.raw_differences[j].begin(), e.raw_differences[j].end());
      }
    };
    add(q.current);
    for (const SecantColumns& e : q.earlier) add(e);
    if (dr.empty()) continue;
    const std::string key = prefix + "iqn/" + std::to_string(k) + "/";
    a.put(key + "counts", counts);
    a.put(key + "residual_differences", dr);
    a.put(key + "raw_differences", dx);
  }
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
  if (options_.first_pass_residual) {
    std::size_t k = 0;
    for (const Stage& s : stages_)
      for (const Transfer& tr : s.after) {
        const std::string key = prefix + "written/" + std::to_string(k);
        if (tr.relaxed && a.has(key)) {
          previous_[k] = a.get(key);
          tr.write(previous_[k]);
        }
        const std::string before = prefix + "written_before/" + std::to_string(k);
        written_before_[k] = tr.relaxed && a.has(before) ? a.get(before) : std::vector<double>{};
        ++k;
      }
    if (options_.first_pass_predictor == FirstPassPredictor::linear) {
      if (!a.has(prefix + "last_interval_ms"))
        throw InputError("checkpoint: no entry '" + prefix + "last_interval_ms': it was written without "
                         "first_pass_predictor = linear");
      last_interval_ms_ = a.scalar(prefix + "last_interval_ms");
    }
  }
  for (std::size_t k = 0; k < iqn_.size(); ++k) {
    QuasiNewtonMemory& q = iqn_[k];
    q = QuasiNewtonMemory{};
    const std::string key = prefix + "iqn/" + std::to_string(k) + "/";
    if (!a.has(key + "counts")) continue;
    const std::vector<double>& counts = a.get(key + "counts");
    const std::vector<double>& dr = a.get(key + "residual_differences");
    const std::vector<double>& dx = a.get(key + "raw_differences", static_cast<long>(dr.size()));
    double columns = 0;
    for (double c : counts) columns += c;
    if (!(columns > 0) || dr.size() % static_cast<std::size_t>(columns) != 0)
      throw InputError("checkpoint: entry '" + key + "residual_differences' does not hold whole columns");
    const std::size_t n = dr.size() / static_cast<std::size_t>(columns);
    std::size_t at = 0;
    for (std::size_t e = 0; e < counts.size(); ++e) {
      SecantColumns cols;
      for (long j = 0; j < static_cast<long>(counts[e]); ++j, at += n) {
        cols.residual_differences.emplace_back(dr.begin() + static_cast<long>(at), dr.begin() + static_cast<long>(at + n));
        cols.raw_differences.emplace_back(dx.begin() + static_cast<long>(at), dx.begin() + static_cast<long>(at + n));
      }
      if (e == 0)
        q.current = std::move(cols);
      else
        q.earlier.push_back(std::move(cols));
    }
  }
}

void Scheduler::advance_to(double t_ms) {
  if (!(t_ms >= time_ms_ - 1e-12 * std::max(1.0, std::abs(time_ms_))))
    throw std::invalid_argument("Scheduler::advance_to: t = " + number(t_ms) + " ms is before the current time " +
                                number(time_ms_) + " ms");
  const double landing = 1e-12 * std::max(1.0, std::abs(t_ms));
  while (t_ms - time_ms_ > landing) {
    const double left = t_ms - time_ms_;
    double t_end = 0;
    if (options_.interval_stage < 0) {
      const double intervals = std::ceil(left / options_.sync_step_ms * (1 - 1e-12));
      t_end = intervals <= 1 ? t_ms : time_ms_ + options_.sync_step_ms;
    } else {
      // The stage's stable step now (a collapsing or non-finite one is sub_cycle's to diagnose:
      // the interval then stays at sync_step_ms and the stage's substeps report it).
      const double limit = stages_[static_cast<std::size_t>(options_.interval_stage)].module->max_step_ms();
      const double step = limit >= options_.min_step_ms && std::isfinite(limit)
                              ? std::min(options_.sync_step_ms, options_.interval_stage_steps * limit)
                              : options_.sync_step_ms;
      const double intervals = std::ceil(left / step * (1 - 1e-12));
      t_end = intervals <= 1 ? t_ms : time_ms_ + left / intervals;
    }
    if (options_.mode == CouplingMode::loose) {
      run_pass(t_end, -1);
    } else {
      for (Stage& s : stages_) s.module->save();
      if (options_.first_pass_predictor == FirstPassPredictor::linear) predict(t_end - time_ms_);
      double residual = 0;
      bool converged = false;
      for (int it = 0; it < options_.strong_max_iterations; ++it) {
        if (it > 0)
          for (Stage& s : stages_) s.module->restore();
        residual = run_pass(t_end, it);
        if ((it > 0 || options_.first_pass_residual) && residual < options_.strong_tolerance) {
          converged = true;
          break;
        }
      }
      if (!converged && options_.strong_max_iterations > 1) ++stats_.unconverged_intervals;
      if (options_.strong_max_iterations > 1) stats_.max_final_residual = std::max(stats_.max_final_residual, residual);
    }
    last_interval_ms_ = t_end - time_ms_;
    time_ms_ = t_end;
    ++stats_.intervals;
  }
}

}  // namespace systole::coupling
