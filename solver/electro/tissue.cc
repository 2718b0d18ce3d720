#include "solver/electro/tissue.h"

#include <omp.h>

#include <chrono>
#include <cmath>
#include <sstream>

#include <time.h>

#include "solver/core/errors.h"

namespace systole::electro {
namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}
// CPU seconds of the calling thread.
double thread_cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// [[A, B], [B^T, C]] with the rows/columns in `pinned` (indices into the full block) replaced
// by the identity: the pinned unknowns are fixed to 0 and the matrix stays symmetric.
SparseMatrix block_with_pins(const SparseMatrix& A, const SparseMatrix& B, const SparseMatrix& C,
                             const std::vector<std::int32_t>& pinned) {
  const Eigen::Index n = A.rows();
  std::vector<char> is_pinned(static_cast<std::size_t>(2 * n), 0);
  for (auto p : pinned) is_pinned[p] = 1;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<std::size_t>(A.nonZeros() + 2 * B.nonZeros() + C.nonZeros()));
  auto add = [&](const SparseMatrix& M, Eigen::Index r0, Eigen::Index c0, bool transpose) {
    for (Eigen::Index k = 0; k < M.outerSize(); ++k)
      for (SparseMatrix::InnerIterator it(M, k); it; ++it) {
        Eigen::Index r = it.row() + r0, c = it.col() + c0;
        if (transpose) std::swap(r, c);
        if (is_pinned[r] || is_pinned[c]) continue;
        t.emplace_back(r, c, it.value());
      }
  };
  add(A, 0, 0, false);
  add(B, 0, n, false);
  add(B, 0, n, true);
  add(C, n, n, false);
  for (auto p : pinned) t.emplace_back(p, p, 1.0);
  SparseMatrix out(2 * n, 2 * n);
  out.setFromTriplets(t.begin(), t.end());
  out.makeCompressed();
  return out;
}

std::unique_ptr<Eigen::SimplicialLDLT<SparseMatrix>> factorise(const SparseMatrix& A, const char* what) {
  auto s = std::make_unique<Eigen::SimplicialLDLT<SparseMatrix>>(A);
  if (s->info() != Eigen::Success)
    throw InstabilityError("electro", what, 0.0, "sparse LDLT factorisation failed");
  return s;
}

// The Nash–Panfilov parameters of the options (tension.h defaults with k_tau and t_scale).
TensionParams tension_params(const TissueOptions& o) {
  if (!(o.tension_time_scale_ms > 0))
    throw InputError("tissue.active_tension_time_scale_ms = " + std::to_string(o.tension_time_scale_ms) +
                     " ms must be > 0");
  TensionParams p = default_tension_params(o.tension_k_kpa);
  p.t_scale_ms = o.tension_time_scale_ms;
  return p;
}

}  // namespace

Formulation formulation_from_name(const std::string& name) {
  if (name == "monodomain") return Formulation::kMonodomain;
  if (name == "bidomain") return Formulation::kBidomain;
  throw InputError("electro.model = '" + name + "' is unknown; known: monodomain, bidomain");
}

Splitting splitting_from_name(const std::string& name) {
  if (name == "godunov") return Splitting::kGodunov;
  if (name == "strang") return Splitting::kStrang;
  throw InputError("electro.splitting = '" + name + "' is unknown; known: godunov, strang");
}

Conductivity monodomain_conductivity(const Conductivity& i, const Conductivity& e) {
  return {i.fibre_ms_per_cm * e.fibre_ms_per_cm / (i.fibre_ms_per_cm + e.fibre_ms_per_cm),
          i.cross_ms_per_cm * e.cross_ms_per_cm / (i.cross_ms_per_cm + e.cross_ms_per_cm)};
}

TissueSolver::TissueSolver(ElectroMesh mesh, TissueOptions options)
    : mesh_(std::move(mesh)),
      options_(std::move(options)),
      activation_({}, options_.activation_threshold_mv),
      tension_(0, tension_params(options_)) {
  mesh_.check();
  const std::size_t n = mesh_.node_count();
  auto positive = [](double v, const char* field, const char* unit) {
    if (!(v > 0)) {
      std::ostringstream os;
      os << field << " = " << v << " " << unit << " must be > 0";
      throw InputError(os.str());
    }
  };
  positive(options_.dt_ms, "electro.time_step_ms", "ms");
  if (options_.threads < 1 || options_.threads > 256)
    throw InputError("electro: threads = " + std::to_string(options_.threads) + " must be in [1, 256]");
  positive(options_.chi_per_cm, "electro.surface_to_volume_per_cm", "1/cm");
  positive(options_.cm_uf_per_cm2, "electro.membrane_capacitance_uf_per_cm2", "uF/cm^2");
  positive(options_.sigma_i.fibre_ms_per_cm, "electro.sigma_i_fibre_ms_per_cm", "mS/cm");
  positive(options_.sigma_i.cross_ms_per_cm, "electro.sigma_i_cross_ms_per_cm", "mS/cm");
  positive(options_.sigma_e.fibre_ms_per_cm, "electro.sigma_e_fibre_ms_per_cm", "mS/cm");
  positive(options_.sigma_e.cross_ms_per_cm, "electro.sigma_e_cross_ms_per_cm", "mS/cm");
  if (options_.domain_cell_models.size() != mesh_.domain_names.size()) {
    std::ostringstream os;
    os << "electro: " << options_.domain_cell_models.size() << " cell models given for "
       << mesh_.domain_names.size() << " mesh domains";
    throw InputError(os.str());
  }

  // --- cell models, one per domain ---
  domains_.resize(mesh_.domain_names.size());
  for (std::size_t i = 0; i < n; ++i) domains_[mesh_.node_domain[i]].nodes.push_back(static_cast<std::int32_t>(i));
  rest_.assign(n, 0.0);
  peak_.assign(n, 0.0);
  vm_.assign(n, 0.0);
  ue_.assign(n, 0.0);
  for (std::size_t d = 0; d < domains_.size(); ++d) {
    Domain& dom = domains_[d];
    dom.model = ionic::make_cell_model(options_.domain_cell_models[d], dom.nodes.size());
    if (options_.dt_ms > dom.model->max_stable_dt_ms() * (1 + 1e-12)) {
      std::ostringstream os;
      os << "electro.time_step_ms = " << options_.dt_ms << " is too large for cell model '" << dom.model->name()
         << "' (domain " << mesh_.domain_names[d] << "): its largest stable step is "
         << dom.model->max_stable_dt_ms() << " ms";
      throw InputError(os.str());
    }
    dom.vm.assign(dom.nodes.size(), 0.0);
    dom.iion.assign(dom.nodes.size(), 0.0);
    for (auto i : dom.nodes) {
      rest_[i] = dom.model->resting_potential_mv();
      peak_[i] = dom.model->peak_potential_mv();
      vm_[i] = rest_[i];
    }
  }
  for (const StimulusSpec& s : options_.stimuli) stimuli_.emplace_back(mesh_, s);
  activation_ = ActivationTracker(rest_, options_.activation_threshold_mv);
  tension_ = ActiveTension(n, tension_params(options_));

  // --- operators (reference configuration, once) ---
  mass_ = assemble_mass(mesh_);
  lumped_ = mass_ * Eigen::VectorXd::Ones(static_cast<Eigen::Index>(n));
  const double c = options_.chi_per_cm * options_.cm_uf_per_cm2;
  const double dts[2] = {options_.dt_ms, 0.5 * options_.dt_ms};
  const double thetas[2] = {1.0, 0.5};
  const int needed = options_.splitting == Splitting::kGodunov ? 0 : 1;
  std::vector<double> cell_scale;  // per-domain conductivity factor, per cell (ours)
  if (!options_.domain_conductivity_scale.empty()) {
    cell_scale.resize(mesh_.cell_count());
    for (std::size_t cc = 0; cc < mesh_.cell_count(); ++cc) {
      const auto d = static_cast<std::size_t>(mesh_.node_domain[static_cast<std::size_t>(mesh_.cell[cc][0])]);
      const double f = d < options_.domain_conductivity_scale.size() ? options_.domain_conductivity_scale[d] : 1.0;
      if (!(f > 0)) throw InputError("domain_conductivity_scale[" + std::to_string(d) + "] = " + std::to_string(f) + ": must be > 0");
      cell_scale[cc] = f;
    }
  }
  if (options_.formulation == Formulation::kMonodomain) {
    k_mono_ = assemble_stiffness(mesh_, monodomain_conductivity(options_.sigma_i, options_.sigma_e), cell_scale);
    const SparseMatrix A = SparseMatrix(mass_ * (c / dts[needed])) + SparseMatrix(k_mono_ * thetas[needed]);
    solve_[needed] = factorise(A, "monodomain diffusion");
  } else {
    k_i_ = assemble_stiffness(mesh_, options_.sigma_i, cell_scale);
    k_sum_ = SparseMatrix(k_i_ + assemble_stiffness(mesh_, options_.sigma_e, cell_scale));
    component_ = mesh_.components();
    std::vector<char> seen;
    for (std::size_t i = 0; i < n; ++i) {
      const auto comp = static_cast<std::size_t>(component_[i]);
      if (comp >= seen.size()) seen.resize(comp + 1, 0);
      if (!seen[comp]) {
        seen[comp] = 1;
        pinned_.push_back(static_cast<std::int32_t>(i));
      }
    }
    std::vector<std::int32_t> pins_block;
    for (auto p : pinned_) pins_block.push_back(p + static_cast<std::int32_t>(n));
    const double th = thetas[needed];
    const SparseMatrix A = SparseMatrix(mass_ * (c / dts[needed])) + SparseMatrix(k_i_ * th);
    const SparseMatrix block = block_with_pins(A, SparseMatrix(k_i_ * th), SparseMatrix(k_sum_ * th), pins_block);
    if (options_.reference_block_solver)
      solve_[needed] = factorise(block, "bidomain block system");
    else
      block_solve_[needed] = std::make_unique<NodePairLdlt>(block, "bidomain block system");
    // Lumped mass per component, summed in node order (zero_mean_ue).
    for (std::size_t i = 0; i < n; ++i) {
      const auto comp = static_cast<std::size_t>(component_[i]);
      if (comp >= ue_weight_.size()) ue_weight_.resize(comp + 1, 0.0);
      ue_weight_[comp] += lumped_[static_cast<Eigen::Index>(i)];
    }
    if (options_.splitting == Splitting::kStrang) {
      // (K_i + K_e) with the same pins, for the explicit half of Crank–Nicolson.
      std::vector<Eigen::Triplet<double>> t;
      std::vector<char> is_pinned(n, 0);
      for (auto p : pinned_) is_pinned[p] = 1;
      for (Eigen::Index k = 0; k < k_sum_.outerSize(); ++k)
        for (SparseMatrix::InnerIterator it(k_sum_, k); it; ++it)
          if (!is_pinned[it.row()] && !is_pinned[it.col()]) t.emplace_back(it.row(), it.col(), it.value());
      for (auto p : pinned_) t.emplace_back(p, p, 1.0);
      SparseMatrix E(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
      E.setFromTriplets(t.begin(), t.end());
      elliptic_ = factorise(E, "bidomain elliptic operator");
    }
  }
}

std::size_t TissueSolver::diffusion_unknowns() const {
  return options_.formulation == Formulation::kMonodomain ? mesh_.node_count() : 2 * mesh_.node_count();
}

void TissueSolver::reaction(double t_ms, double dt_ms) {
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_s();
  // Gather Vm, advance the cell model, scatter -dt Iion: per node, so disjoint node ranges are
  // independent and run on options_.threads OpenMP threads. A zero-length compute() first lets
  // a model build its per-dt tables (TTP06 lookup table) before the threads read them.
  auto advance = [&](Domain& d, std::size_t b, std::size_t e) {
    for (std::size_t k = b; k < e; ++k) d.vm[k] = vm_[d.nodes[k]];
    d.model->compute({b, e}, dt_ms, d.vm.data(), d.iion.data());
    for (std::size_t k = b; k < e; ++k) vm_[d.nodes[k]] -= dt_ms * d.iion[k];
  };
  for (Domain& d : domains_) {
    const std::size_t n = d.nodes.size();
    if (options_.threads > 1 && n >= 64) {
      d.model->compute({0, 0}, dt_ms, d.vm.data(), d.iion.data());
#pragma omp parallel num_threads(options_.threads)
      {
        const auto t = static_cast<std::size_t>(omp_get_thread_num());
        const auto nt = static_cast<std::size_t>(omp_get_num_threads());
        advance(d, n * t / nt, n * (t + 1) / nt);
      }
    } else {
      advance(d, 0, n);
    }
  }
  const double t_mid = t_ms + 0.5 * dt_ms;
  for (const Stimulus& s : stimuli_) {
    const double a = s.amplitude_at(t_mid);
    if (a == 0.0) continue;
    for (auto i : s.nodes()) vm_[i] += dt_ms * a / options_.cm_uf_per_cm2;
  }
  reaction_s_ += seconds_since(t0);
  reaction_cpu_s_ += thread_cpu_s() - cpu0;
}

void TissueSolver::zero_mean_ue() {
  std::vector<double>& sum = ue_sum_;
  sum.assign(ue_weight_.size(), 0.0);
  for (std::size_t i = 0; i < ue_.size(); ++i)
    sum[component_[i]] += lumped_[static_cast<Eigen::Index>(i)] * ue_[i];
  for (std::size_t i = 0; i < ue_.size(); ++i) ue_[i] -= sum[component_[i]] / ue_weight_[component_[i]];
}

void TissueSolver::diffusion(double tau_ms, double theta) {
  const auto t0 = Clock::now();
  const double cpu0 = thread_cpu_s();
  const auto n = static_cast<Eigen::Index>(mesh_.node_count());
  const double c = options_.chi_per_cm * options_.cm_uf_per_cm2;
  const Eigen::Map<Eigen::VectorXd> v(vm_.data(), n);
  if (options_.formulation == Formulation::kMonodomain) {
    const Solver& S = *solve_[theta == 1.0 ? 0 : 1];
    Eigen::VectorXd rhs = mass_ * v * (c / tau_ms);
    if (theta < 1.0) rhs -= (1.0 - theta) * (k_mono_ * v);
    const Eigen::VectorXd x = S.solve(rhs);
    Eigen::Map<Eigen::VectorXd>(vm_.data(), n) = x;
  } else {
    Eigen::VectorXd& rhs = rhs_;
    rhs.resize(2 * n);
    rhs.tail(n).setZero();
    rhs.head(n) = mass_ * v * (c / tau_ms);
    if (theta < 1.0) {
      // Explicit half: -K_i (v + u_e*) with u_e* solving the elliptic equation for this v.
      Eigen::VectorXd b = -(k_i_ * v);
      for (auto p : pinned_) b[p] = 0.0;
      const Eigen::VectorXd ue_star = elliptic_->solve(b);
      rhs.head(n) -= (1.0 - theta) * (k_i_ * (v + ue_star));
    }
    for (auto p : pinned_) rhs[n + p] = 0.0;
    const int which = theta == 1.0 ? 0 : 1;
    if (block_solve_[which])
      block_solve_[which]->solve(rhs, x_);
    else
      x_ = solve_[which]->solve(rhs);
    Eigen::Map<Eigen::VectorXd>(vm_.data(), n) = x_.head(n);
    Eigen::Map<Eigen::VectorXd>(ue_.data(), n) = x_.tail(n);
    zero_mean_ue();
  }
  diffusion_s_ += seconds_since(t0);
  diffusion_cpu_s_ += thread_cpu_s() - cpu0;
}

void TissueSolver::export_state(StateArchive& a, const std::string& prefix) const {
  a.put_scalar(prefix + "time_ms", t_ms_);
  a.put(prefix + "vm_mv", vm_);
  a.put(prefix + "ue_mv", ue_);
  for (std::size_t d = 0; d < domains_.size(); ++d) {
    const std::string dp = prefix + "domain_" + std::to_string(d) + "/";
    const ionic::CellModel& m = *domains_[d].model;
    for (std::size_t k = 0; k < m.state_count(); ++k) a.put(dp + std::to_string(k), m.state(k));
    a.put(dp + "vm_mv", domains_[d].vm);
    a.put(dp + "iion", domains_[d].iion);
  }
  a.put(prefix + "activation_ms", activation_.activation_ms());
  a.put(prefix + "repolarisation_ms", activation_.repolarisation_ms());
  a.put(prefix + "activation_peak_mv", activation_.peak_mv());
  a.put(prefix + "tension_kpa", tension_.tension_kpa());
}

void TissueSolver::import_state(const StateArchive& a, const std::string& prefix) {
  const long n = static_cast<long>(vm_.size());
  t_ms_ = a.scalar(prefix + "time_ms");
  vm_ = a.get(prefix + "vm_mv", n);
  ue_ = a.get(prefix + "ue_mv", n);
  for (std::size_t d = 0; d < domains_.size(); ++d) {
    const std::string dp = prefix + "domain_" + std::to_string(d) + "/";
    ionic::CellModel& m = *domains_[d].model;
    const long nd = static_cast<long>(domains_[d].nodes.size());
    for (std::size_t k = 0; k < m.state_count(); ++k) m.state(k) = a.get(dp + std::to_string(k), nd);
    domains_[d].vm = a.get(dp + "vm_mv", static_cast<long>(domains_[d].vm.size()));
    domains_[d].iion = a.get(dp + "iion", static_cast<long>(domains_[d].iion.size()));
  }
  activation_.restore(a.get(prefix + "activation_ms", n), a.get(prefix + "repolarisation_ms", n),
                      a.get(prefix + "activation_peak_mv", n));
  tension_.restore(a.get(prefix + "tension_kpa", n));
}

void TissueSolver::step() {
  const double dt = options_.dt_ms;
  const std::vector<double> v_old = vm_;
  if (options_.splitting == Splitting::kGodunov) {
    reaction(t_ms_, dt);
    diffusion(dt, 1.0);
  } else {
    diffusion(0.5 * dt, 0.5);
    reaction(t_ms_, dt);
    diffusion(0.5 * dt, 0.5);
  }
  for (std::size_t i = 0; i < vm_.size(); ++i) {
    if (!(std::abs(vm_[i]) <= 1000.0)) {
      std::ostringstream os;
      os << "Vm = " << vm_[i] << " mV (outside [-1000, 1000] mV); reduce electro.time_step_ms";
      throw InstabilityError("electro", "node " + std::to_string(i), (t_ms_ + dt) * 1e-3, os.str());
    }
  }
  activation_.update(t_ms_, v_old, t_ms_ + dt, vm_);
  tension_.advance(dt, vm_, rest_, peak_);
  t_ms_ += dt;
}

}  // namespace systole::electro
