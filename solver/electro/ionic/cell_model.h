#pragma once
// Cell (ionic) models behind one narrow interface, shaped like openCARP's limpet
// (docs/architecture.md, house style 5):
// - a model owns its Params (named, overridable, listable) and its State, stored as a
//   structure of arrays over the nodes it serves (state[k][node]);
// - compute(range, dt) reads the transmembrane potential Vm (mV) of those nodes, advances the
//   state by dt (gating variables by Rush–Larsen, the rest by forward Euler, both exactly as
//   stated per model) and writes the ionic current Iion of each node;
// - Iion is per unit membrane capacitance, in uA/uF (= mV/ms, the limpet convention): the
//   membrane equation of a single cell is dVm/dt = -(Iion + Istim / C_m).
// - every model declares the largest time step at which its compute() is stable
//   (max_stable_dt_ms): tissue solvers reject a larger step with an InputError.
// The registry (make_cell_model / cell_model_names) lists every model; an unknown name is an
// InputError listing the known ones.
#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace systole::electro::ionic {

// One named model parameter: value, unit and what it is (with its source).
struct ParamInfo {
  std::string name;
  double value;
  std::string unit;
  std::string doc;
};

// A half-open range of node indices [begin, end).
struct NodeRange {
  std::size_t begin;
  std::size_t end;
};

class CellModel {
 public:
  virtual ~CellModel() = default;

  // Registry name ("ttp06_epi", "fhn", ...).
  virtual std::string_view name() const = 0;
  // Names of the state variables (state(k) follows this order).
  virtual std::vector<std::string> state_names() const = 0;
  // Initial (resting) transmembrane potential, mV; every node starts there.
  virtual double resting_potential_mv() const = 0;
  // Nominal action-potential peak, mV: with the resting potential it defines the normalised
  // potential (Vm - rest) / (peak - rest) of the active-tension model (eq 23).
  virtual double peak_potential_mv() const = 0;
  // Largest dt (ms) at which compute() is stable for this model (declared, see each model).
  virtual double max_stable_dt_ms() const = 0;

  // Advances the state of the nodes in `range` by dt_ms at the given potentials and writes
  // iion[node] (uA/uF) for those nodes. vm_mv and iion are indexed by node (size() entries).
  // The potential is NOT changed here: the caller integrates dVm/dt = -Iion (+ diffusion).
  // Calls on disjoint ranges may run concurrently once compute() has been called with this dt
  // (a zero-length range is enough: per-dt tables are built then, not per node).
  virtual void compute(NodeRange range, double dt_ms, const double* vm_mv, double* iion) = 0;

  // --- parameters (limpet-style: by name) ---
  std::vector<ParamInfo> parameters() const { return params_; }
  double parameter(std::string_view name) const;
  // Throws InputError naming the model, the parameter and the known parameter names. Must be
  // called before the first compute(); resets the state to the model's initial state.
  void set_parameter(std::string_view name, double value);

  // --- state (SoA) ---
  std::size_t size() const { return nodes_; }
  std::size_t state_count() const { return state_.size(); }
  const std::vector<double>& state(std::size_t k) const { return state_[k]; }
  std::vector<double>& state(std::size_t k) { return state_[k]; }
  // Index of a named state variable; throws InputError if unknown.
  std::size_t state_index(std::string_view name) const;
  // Puts every node in the model's initial state.
  void reset();

 protected:
  CellModel(std::size_t nodes, std::vector<ParamInfo> params);
  // Initial value of every state variable, in state_names() order (after parameter changes).
  virtual std::vector<double> initial_state() const = 0;
  // Called after a parameter changed: refresh cached constants.
  virtual void on_parameters_changed() {}
  // Fast access for derived classes (index into params_ fixed at construction).
  double p(std::size_t i) const { return params_[i].value; }
  // Allocates state_names().size() arrays; derived constructors call it last.
  void allocate_state();

  std::vector<std::vector<double>> state_;

 private:
  std::size_t nodes_;
  std::vector<ParamInfo> params_;
};

// --- registry ---------------------------------------------------------------------------

// Registry names, in a fixed order: aliev_panfilov, mitchell_schaeffer, fhn, fhn_atrial (ours:
// FHN with a 30x faster Vm equation, atrial CV), ttp06 (= ttp06_epi), ttp06_endo, ttp06_mid,
// ttp06_epi.
const std::vector<std::string>& cell_model_names();
// A model for `nodes` nodes in its initial state. Throws InputError("unknown cell model
// 'x'; known: ...") for an unknown name.
std::unique_ptr<CellModel> make_cell_model(std::string_view name, std::size_t nodes);

// Rush–Larsen update of a gate with steady state x_inf and time constant tau_ms (exact for
// frozen Vm): x(t + dt) = x_inf - (x_inf - x) exp(-dt / tau).
inline double rush_larsen(double x, double x_inf, double tau_ms, double dt_ms);

}  // namespace systole::electro::ionic

#include <cmath>
namespace systole::electro::ionic {
inline double rush_larsen(double x, double x_inf, double tau_ms, double dt_ms) {
  return x_inf - (x_inf - x) * std::exp(-dt_ms / tau_ms);
}
}  // namespace systole::electro::ionic
