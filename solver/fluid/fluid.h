#pragma once
// Incompressible Navier–Stokes on the staggered grid of solver/grid (MODEL.md §3, eq 1–2, 8–10),
// nondimensional with d_m and U_m (Re = U_m d_m / ν). One FluidSolver owns the fluid state of
// this rank's slab: velocity at faces, pressure at cell centres, the AB2 history, the Poisson
// solver. Nothing here knows about hearts: coupling/ adds forces through the body-force hook.
#include <array>
#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "solver/fluid/pressure/poisson.h"
#include "solver/fluid/viscosity.h"
#include "solver/grid/grid.h"

namespace systole::fluid {

enum class WallKind { no_slip, free_slip };
// One z wall. no_slip: u = (velocity_x, velocity_y, 0) on the wall (a moving wall drives
// Couette flow); free_slip: ∂u/∂z = ∂v/∂z = 0, w = 0 (ours: verification of periodic flows).
struct Wall {
  WallKind kind = WallKind::no_slip;
  double velocity_x = 0, velocity_y = 0;  // nondimensional, no_slip only
};

// An axis-aligned box of the Darcy sink (ours: the seed's region is "near the end of the
// thoracic aorta"; coupling/ may pass several boxes). Nondimensional coordinates.
struct DarcyRegion {
  double x_min = 0, x_max = 0, y_min = 0, y_max = 0, z_min = 0, z_max = 0;
};

// Parameters, nondimensional unless the name says otherwise. Checked by validate().
struct FluidParameters {
  double reynolds = 3000;           // Re = U_m d_m / ν, (0, 1e7]; seed 3000
  double cfl = 0.2;                 // target CFL number, (0, 1]; seed 0.2
  // How the CFL number of a velocity field is measured. "component_maxima" (ours, conservative):
  // Δt (max|u|/dx + max|v|/dy + max|w|/dz), each maximum over the whole field, so the three
  // may come from three different places. "per_cell" (the seed's codes' local form, e.g. AFiD's
  // CalcMaxCFL): Δt max over cells of (|u|/dx + |v|/dy + |w|/dz), here at each cell's lower
  // faces (ours: AFiD averages each cell's two faces). per_cell ≤ component_maxima, equal
  // when one cell holds all three maxima. The abort on a realised CFL keeps component_maxima.
  std::string cfl_rule = "component_maxima";
  double max_dt = 0.0025;           // largest step, > 0 (0.1 ms at d_m/U_m = 40 ms)
  bool adaptive_dt = true;          // false: every step is max_dt (convergence studies)
  double viscous_safety = 0.5;      // Δt ≤ viscous_safety/(ν Σ 4/Δ²), (0, 1] (ours)
  double darcy_permeability = 0.001;        // k of the sink −u/k, > 0; seed 0.001
  std::vector<DarcyRegion> darcy_regions;   // where the sink acts; empty: nowhere
  Wall bottom_wall, top_wall;
  // "newtonian": ν = 1/reynolds. "carreau_yasuda": ν(γ̇) from carreau_yasuda (viscosity.h), the
  // viscous term in divergence form ∇·[ν(γ̇)(∇u + ∇uᵀ)]; reynolds is then only a reference value
  // (the verification cases size their forcing with it).
  std::string viscosity_model = "newtonian";
  CarreauYasuda carreau_yasuda = blood_carreau_yasuda();  // nondimensional; default: blood
  // Subgrid eddy viscosity (ours; the seed's runs are DNS): "none", or "vreman": ν = 1/reynolds
  // + ν_e with Vreman's ν_e (viscosity.h) from the resolved gradient, constant subgrid_constant,
  // through the same divergence-form variable-viscosity term as Carreau–Yasuda. Newtonian only.
  std::string subgrid_model = "none";
  double subgrid_constant = 0.07;   // Vreman's c, (0, 1]; 0.07 ≈ 2.5 C_s² with C_s = 0.17
  double time_scale_s = 0.04;       // d_m/U_m, only to report times in seconds
  double length_scale_mm = 24;      // d_m, only to report places in mm
  double abort_cfl = 1.0;           // realised CFL above which a step is declared unstable (ours)
  double abort_energy_growth = 10;  // kinetic-energy ratio per step declared unstable (ours)
  // The growth check applies only above this volume-mean ½|u|² (ours): a motion starting from
  // rest grows by large factors at negligible energy (an IB body set moving, a body force
  // switched on), which is not a blow-up. 1e-4 = an rms speed of 0.014 U_m. [0, inf).
  double abort_energy_floor = 1e-4;
  // A CFL- or viscosity-limited step below this stops the run (InstabilityError naming the
  // fastest cell, ours): velocities that grow while the adaptive step shrinks keep the realised
  // CFL at its target, so without it a blowing-up run crawls on instead of stopping. 0: off. [0, max_dt).
  double abort_min_dt = 0;
};

// Throws InputError naming the field, its value and the allowed range.
void validate(const FluidParameters& p, const grid::Grid& g);

struct Velocity {
  explicit Velocity(const grid::Slabs& s) : u(s), v(s), w(s) {}
  grid::XFaceField u;
  grid::YFaceField v;
  grid::ZFaceField w;
};

struct StepContext {
  double time = 0;  // t_n, the start of the step
  double dt = 0;    // Δt of the step
  long step = 0;    // n (steps taken before this one)
};
// The body-force hook (eq 8): called once per step with the provisional velocity û (halos
// valid, wall conditions applied) and f zeroed; it adds its force density to f on this rank's
// interior faces. The step then sets u* = û + Δt f before the projection. A prescribed f(t)
// should be evaluated at t_n + Δt/2 to keep second order in time. Collective if it wants.
using BodyForce = std::function<void(const StepContext&, const Velocity& u_hat, Velocity& f)>;

struct FlowDiagnostics {
  double kinetic_energy = 0;   // volume mean of ½|u|²
  // The exact discrete energy sink of the viscous term: Newtonian, ν × volume mean of |∇u|²
  // (wall differences included); Carreau–Yasuda, the volume mean of ν(γ̇) 2S:S summed over
  // the cells (normal strains) and cell edges (shear strains) where the operator puts them.
  double dissipation = 0;
  double max_divergence = 0;   // max |∇·u| over cells
  double max_speed = 0;        // max(|u|,|v|,|w|) over faces
};

class FluidSolver {
 public:
  // Validates, builds the Poisson solver (its constructor self-test included); the fluid is
  // at rest, t = 0. Collective on slabs.comm().
  FluidSolver(const grid::Slabs& slabs, FluidParameters parameters);
  ~FluidSolver();

  // Sets u(x,y,z) (each component sampled at its own faces), projects it onto the discretely
  // divergence-free fields, zeroes p and the AB2 history, keeps t. Collective.
  using VelocityFunction = std::function<double(double x, double y, double z)>;
  void set_velocity(const VelocityFunction& u, const VelocityFunction& v, const VelocityFunction& w);
  // Sets p(x,y,z) at the cell centres (an initial state, e.g. hydrostatic under a uniform body
  // force; the next projection keeps it as the starting pressure of eq 10). Halos exchanged.
  // Collective.
  void set_pressure(const VelocityFunction& p);
  void set_body_force(BodyForce force);
  void set_time(double t) { time_ = t; }

  // One step of eq 1–2, 8–10; returns the Δt taken (never more than t_limit − t). Throws
  // InstabilityError ("fluid", place, time) on non-finite values, a realised CFL above
  // abort_cfl or a kinetic-energy jump above abort_energy_growth; the state is then garbage.
  double advance(double t_limit = 1e300);
  // Steps until t_end (the last step shortened to land on it). Returns the steps taken.
  long advance_to(double t_end);

  FlowDiagnostics diagnostics() const;  // collective
  // Volume flux ∫u dy dz through every x-face plane i (global, size nx): equal for all i
  // when mass is conserved. Collective.
  std::vector<double> volume_flux_x() const;

  // Checkpoint of the whole state (velocity, pressure, AB2 history, time, step, last Δt) in
  // HDF5; restore makes the continued run equal a straight run bitwise. Collective.
  void write_checkpoint(const std::filesystem::path& file) const;
  void restore_checkpoint(const std::filesystem::path& file);
  // The same state in memory, for strong coupling's repeated intervals (coupling::FluidModule):
  // a run continued after restore_state(s) equals the run continued after save_state(s)
  // bitwise. Each rank saves its own slab (not collective). The body-force hook is not state.
  struct State {
    explicit State(const grid::Slabs& slabs) : vel(slabs), h_prev(slabs), p(slabs) {}
    Velocity vel, h_prev;
    grid::CellField p;
    double time = 0, dt_prev = 0, kinetic_energy = 0, nu_max = 0;
    double max_u = 0, max_v = 0, max_w = 0, max_cell_rate = 0;  // pick the next Δt
    long steps = 0;
    bool have_history = false;
  };
  void save_state(State& out) const;
  void restore_state(const State& in);
  // The Δt the next advance() would take without a time limit (CFL, viscous bound, max_dt),
  // nondimensional. Carreau–Yasuda: with the largest ν of the last step (advance() updates ν
  // first, so its step can be smaller).
  double stable_step() const { return choose_time_step(1e300); }
  // The step the CFL target cfl (in (0, 1]; InputError otherwise, naming it) would choose from
  // the current state, with the same viscous bound and max_dt (ours: coupling::FluidModule's
  // carry-over reference step). Without adaptive_dt: max_dt. Never stops the run (abort_min_dt is
  // stable_step()'s check).
  double step_at_cfl(double cfl) const;
  // Velocity, pressure and vorticity at cell centres (+ XDMF sidecar for ParaView), the ones
  // `which` selects. Collective.
  // Which fields, in which units: the values written are the nondimensional ones times the
  // scales (1: nondimensional), and write_xdmf adds <file>.xmf (rank 0) for the grid in
  // nondimensional lengths. The dataset names do not change with the scales.
  struct FieldSelection {
    bool velocity = true, pressure = true, vorticity = true;
    double velocity_scale = 1, pressure_scale = 1, vorticity_scale = 1;
    bool write_xdmf = true;
    int gzip_level = 0;  // > 0: shuffle + gzip at this level (grid::FieldFile::set_compression)
  };
  void write_fields(const std::filesystem::path& h5_file, FieldSelection which) const;
  void write_fields(const std::filesystem::path& h5_file) const { write_fields(h5_file, FieldSelection{}); }

  const Velocity& velocity() const { return vel_; }
  const grid::CellField& pressure() const { return p_; }
  double time() const { return time_; }
  long steps() const { return steps_; }
  double last_dt() const { return dt_prev_; }
  // The largest |u|, |v|, |w| after the last step (each over its own faces; they set the next
  // step's CFL bound), nondimensional.
  std::array<double, 3> max_velocity() const { return {max_u_, max_v_, max_w_}; }
  // The cell with the largest |u|/dx + |v|/dy + |w|/dz (its lower faces), as
  // "(i,j,k) = (...) at (x, y, z) mm". Collective.
  std::string fastest_cell() const;
  const FluidParameters& parameters() const { return par_; }
  const grid::Slabs& slabs() const { return slabs_; }
  const PoissonSolver& poisson() const { return *poisson_; }
  std::size_t bytes_allocated() const;
  std::vector<std::string> warnings() const { return poisson_->warnings(); }
  bool variable_viscosity() const { return nu_ != nullptr; }
  // Carreau–Yasuda or a subgrid model: the largest ν over the cells (wall ghosts included) at the
  // start of the last step, the one that limited its Δt; 1/reynolds when Newtonian without one.
  double max_viscosity() const { return nu_ ? nu_max_ : 1.0 / par_.reynolds; }

 private:
  void apply_velocity_boundary_conditions(Velocity& vel) const;
  double choose_time_step(double t_limit) const;
  double step_bound(double cfl) const;  // min(max_dt, cfl / rate, the viscous bound); max_dt without adaptive_dt
  void compute_explicit_terms();                    // H = −∇·(uu) + Re⁻¹∇²u   (eq 1–2)
  template <bool kNewtonianViscous>
  void explicit_terms_kernel();                     // advection (+ Re⁻¹∇²u when Newtonian)
  void update_viscosity();                          // ν at cells + wall ghosts, max ν
  double compute_viscosity(grid::CellField& nu) const;  // → local max ν
  double variable_viscosity_dissipation() const;
  void add_variable_viscous_term();                 // H += ∇·[ν(∇u + ∇uᵀ)]
  void predict(double dt, double gamma, double rho);  // û = u + Δt(γH + ρH') − αΔt∇p
  void add_body_force(double dt);                   // u* = û + Δt f            (eq 8)
  void apply_darcy_sink(double dt);                 // u* ← u*/(1 + Δt/k) in the region (ours)
  void project(double dt);                          // ∇²φ = ∇·u*/(αΔt), u = u* − αΔt∇φ (eq 9)
  void update_pressure();                           // p ← p + φ                (eq 10)
  void check_stability(double dt);

  const grid::Slabs& slabs_;
  FluidParameters par_;
  std::unique_ptr<PoissonSolver> poisson_;
  Velocity vel_;
  grid::CellField p_, phi_, rhs_;
  std::unique_ptr<Velocity> h_, h_prev_;  // explicit terms at n and n−1
  std::unique_ptr<Velocity> force_;       // allocated when a body force is set
  std::unique_ptr<grid::CellField> nu_;   // ν at cell centres (Carreau–Yasuda only)
  double nu_max_ = 0;
  BodyForce body_force_;
  double time_ = 0, dt_prev_ = 0;
  long steps_ = 0;
  bool have_history_ = false;
  double kinetic_energy_ = 0;
  double max_u_ = 0, max_v_ = 0, max_w_ = 0;  // over faces, after the last step
  double max_cell_rate_ = 0;                  // max over cells of |u|/dx + |v|/dy + |w|/dz (lower faces)
};

}  // namespace systole::fluid
