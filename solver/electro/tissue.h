#pragma once
// Tissue electrophysiology on an ElectroMesh: monodomain or bidomain (eq 21–22, MODEL.md §6),
// operator splitting of the reaction (cell models, stimuli) and the diffusion (implicit P1 FEM):
//
//   bidomain:   chi (C_m dv/dt + C_m Iion) + I_s = div(M_i grad v) + div(M_i grad u_e)     (21a)
//               0 = div(M_i grad v + (M_i + M_e) grad u_e)                                (21b)
//   monodomain: chi (C_m dv/dt + C_m Iion) + I_s = div(M grad v),
//               M = M_i M_e (M_i + M_e)^-1 (fibre-wise harmonic mean: exact for proportional
//               tensors, the usual choice otherwise; ours)
// with M = sigma_c I + (sigma_f - sigma_c) f f^T (eq 22), Iion in uA/uF from the cell model,
// I_s the stimuli (uA/cm^2 of membrane, entering as -chi I_s with "> 0 depolarises").
//
// One step of length dt (step()):
//   Godunov: R(dt) then D(dt) by backward Euler                       (first order)
//   Strang:  D(dt/2) by Crank–Nicolson, R(dt), D(dt/2) by Crank–Nicolson (second order)
// R(dt): per node, Vm += dt (-Iion + I_s / C_m) with the cell model's state advanced by dt
//        (Rush–Larsen gates), explicit in Vm;
// D(tau): (chi C_m M/tau + theta K) v^{n+1} = (chi C_m M/tau - (1-theta) K) v^n (monodomain),
//        the bidomain as one symmetric block system in (v, u_e) with u_e pinned at one node of
//        each connected component (its null space), then shifted to zero mean per component.
// Every matrix is assembled and factorised once, at construction: Eigen SimplicialLDLT for the
// monodomain and elliptic operators; the bidomain block system by NodePairLdlt (node-interleaved
// AMD ordering, 2 x 2 blocked triangular solves, node_pair_ldlt.h; ours), the same system and
// solution to round-off, about 3.6x cheaper per solve than SimplicialLDLT on the default heart.
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include "solver/core/state_archive.h"
#include "solver/electro/activation.h"
#include "solver/electro/fem.h"
#include "solver/electro/ionic/cell_model.h"
#include "solver/electro/mesh.h"
#include "solver/electro/node_pair_ldlt.h"
#include "solver/electro/stimulus.h"
#include "solver/electro/tension.h"

namespace systole::electro {

enum class Formulation { kMonodomain, kBidomain };
enum class Splitting { kGodunov, kStrang };
// "monodomain"/"bidomain", "godunov"/"strang"; InputError listing the options otherwise.
Formulation formulation_from_name(const std::string& name);
Splitting splitting_from_name(const std::string& name);

struct TissueOptions {
  Formulation formulation;
  Splitting splitting;
  double dt_ms;
  double chi_per_cm;
  double cm_uf_per_cm2;
  Conductivity sigma_i, sigma_e;
  std::vector<std::string> domain_cell_models;  // one registry name per mesh domain
  std::vector<StimulusSpec> stimuli;
  double activation_threshold_mv;  // e.g. -40 mV
  double tension_k_kpa;            // Nash–Panfilov amplitude k_tau (eq 23)
  double tension_time_scale_ms = 12.9;  // Nash–Panfilov time unit t_scale (eq 23, tension.h)
  // Optional factor (> 0) on sigma_i and sigma_e per mesh domain (empty: 1 everywhere); a cell
  // takes the factor of its first node's domain (ours; e.g. the atrial conductivity scale).
  std::vector<double> domain_conductivity_scale = {};
  // OpenMP threads of the reaction step (cell models over disjoint node ranges), in [1, 256];
  // the diffusion solve stays serial (ours). 1: no threading.
  int threads = 1;
  // Verification only (tests, bench): solve the bidomain block system with Eigen's
  // SimplicialLDLT (AMD on the 2n unknowns), the solver before NodePairLdlt (ours).
  bool reference_block_solver = false;
};

// The monodomain conductivity of a (sigma_i, sigma_e) pair (fibre-wise harmonic mean).
Conductivity monodomain_conductivity(const Conductivity& sigma_i, const Conductivity& sigma_e);

class TissueSolver {
 public:
  // Validates everything (InputError): mesh, positive chi, C_m, dt and conductivities, one
  // known cell model per domain, dt <= every model's max_stable_dt_ms, every stimulus region
  // non-empty. Assembles and factorises the diffusion operators.
  TissueSolver(ElectroMesh mesh, TissueOptions options);

  // Advances by one dt. Throws InstabilityError("electro", ...) if Vm leaves [-1000, 1000] mV
  // or becomes NaN.
  void step();
  // Checkpoints: the whole evolving state (Vm, u_e, every domain's cell-model state, the
  // activation tracker, the active tension, the clock) under `prefix`. import_state() of what
  // export_state() wrote, into a solver built from the same mesh and options, continues
  // bitwise as the exporting solver would; InputError for a missing entry or another size.
  void export_state(StateArchive& archive, const std::string& prefix) const;
  void import_state(const StateArchive& archive, const std::string& prefix);
  double time_ms() const { return t_ms_; }
  double dt_ms() const { return options_.dt_ms; }

  const ElectroMesh& mesh() const { return mesh_; }
  const TissueOptions& options() const { return options_; }
  const std::vector<double>& vm_mv() const { return vm_; }
  // Extracellular potential (bidomain; zero mean per connected component). Zeros for monodomain.
  const std::vector<double>& ue_mv() const { return ue_; }
  ActivationTracker& activation() { return activation_; }
  const ActivationTracker& activation() const { return activation_; }
  // Nash–Panfilov active tension per node, kPa: the accessor for the structure module.
  const std::vector<double>& active_tension_kpa() const { return tension_.tension_kpa(); }
  ionic::CellModel& cell_model(std::size_t domain) { return *domains_.at(domain).model; }
  const std::vector<double>& resting_mv() const { return rest_; }
  // Unknowns of the diffusion solve (n monodomain, 2n bidomain).
  std::size_t diffusion_unknowns() const;
  // Wall-clock seconds spent in the reaction and diffusion stages so far.
  double reaction_seconds() const { return reaction_s_; }
  double diffusion_seconds() const { return diffusion_s_; }
  // CPU seconds of the calling thread in the same stages (the reaction's other OpenMP threads
  // not counted): the costs on a shared machine (bench/electro/bidomain_cost.cc).
  double reaction_cpu_seconds() const { return reaction_cpu_s_; }
  double diffusion_cpu_seconds() const { return diffusion_cpu_s_; }

 private:
  struct Domain {
    std::vector<std::int32_t> nodes;
    std::unique_ptr<ionic::CellModel> model;
    std::vector<double> vm, iion;
  };
  using Solver = Eigen::SimplicialLDLT<SparseMatrix>;

  void reaction(double t_ms, double dt_ms);
  void diffusion(double tau_ms, double theta);
  void zero_mean_ue();

  ElectroMesh mesh_;
  TissueOptions options_;
  std::vector<Domain> domains_;
  std::vector<Stimulus> stimuli_;
  std::vector<double> vm_, ue_, rest_, peak_;
  double t_ms_ = 0;

  SparseMatrix mass_, k_i_, k_sum_, k_mono_;
  Eigen::VectorXd lumped_;
  std::vector<std::int32_t> component_, pinned_;  // pinned_: one node per component
  // Factorised operators: [0] backward Euler over dt, [1] Crank–Nicolson over dt/2; the
  // bidomain block system in block_solve_ (or solve_ with options_.reference_block_solver).
  std::unique_ptr<Solver> solve_[2];
  std::unique_ptr<NodePairLdlt> block_solve_[2];
  Eigen::VectorXd rhs_, x_;          // bidomain diffusion workspaces (2n)
  std::vector<double> ue_weight_, ue_sum_;  // per connected component: lumped mass, workspace
  std::unique_ptr<Solver> elliptic_;  // bidomain + Strang: (K_i + K_e) u_e = -K_i v
  ActivationTracker activation_;
  ActiveTension tension_;
  double reaction_s_ = 0, diffusion_s_ = 0, reaction_cpu_s_ = 0, diffusion_cpu_s_ = 0;
};

}  // namespace systole::electro
