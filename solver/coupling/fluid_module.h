#pragma once
// The fluid with its immersed bodies (solver/fluid + solver/ibm) as a coupling::Module: the fluid
// stage of the seed's Fig. 6 (MODEL.md §3–4, §7), for the fsi and fsei scenes.
//
// Contract
// - The scene owns the FluidSolver, the Markers and the DirectForcing (built on the fluid's
//   slabs and those markers). The module installs the forcing in the fluid's body-force hook at
//   construction and is from then on the hook's only user.
// - Clock: the fluid's nondimensional time × time_scale_ms (d_m/U_m in ms: 40 ms in the seed).
// - max_step_ms(): the fluid's stable step (FluidSolver::stable_step: CFL, viscous bound,
//   max_dt) from the current state, in ms. step(dt_ms): exactly one fluid step of dt_ms (eq 1–2,
//   8–10 with the direct forcing of eq 3). Asked for more than its limit (only the scheduler's
//   test hook does), the fluid takes its own smaller step and the module's clock falls short of
//   the target; the scheduler then sub-cycles on. The fluid throws InstabilityError ("fluid", the
//   cell, the time) on a blow-up; its state is then garbage and the run stops.
// - Inputs, held over the substeps of a synchronisation interval: the node positions and
//   velocities of each deformable immersed body (set_body_nodes, grid units = d_m), written by
//   the scene's transfers from the structure. Stencils are rebuilt before the next step when a
//   body moved. Rigid bodies keep what the scene set on the Markers.
// - Outputs, at a synchronisation point: loads() = the hydrodynamic loads on every marker
//   (eq 11–14) and the wall shear stress (eq 27) of the current state. The DV_b/Dt term of eq 14
//   is taken as 0 (ours, this version: the structure hands over positions and velocities only).
// - save()/restore(): the fluid's whole state in memory (FluidSolver::State) and the forcing's
//   carried force (ibm::DirectForcing::carried_force, the carry-over's state), bitwise; the
//   marker nodes are inputs, not state, and are kept (Module contract).
#include <string>
#include <vector>

#include "solver/coupling/module.h"
#include "solver/fluid/fluid.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/loads.h"
#include "solver/ibm/markers.h"

namespace systole::coupling {

struct FluidModuleOptions {
  double time_scale_ms = 40.0;  // d_m / U_m in ms, > 0 (seed: 24 mm / 0.6 m/s)
  // A uniform body-force density g added to the momentum equation (nondimensional, ρU²/d_m)
  // (ours: a driving pressure gradient or gravity for verification; 0 in the heart scenes). The
  // markers see û + Δt g, so the forcing cancels it inside the bodies.
  ibm::Vec3 uniform_force_density = ibm::Vec3::Zero();
  // The carry-over's step-aware increment share (ours), [0, 1]; 0: off. Each fluid step's forcing
  // multiplies ibm::ForcingParameters::carry_over_increment_share by
  // w = min(1, Δt(cfl) / Δt(carry_over_reference_cfl)), the two the fluid's stable steps from the
  // step's state at its own CFL target and at this one (FluidSolver::step_at_cfl): the carried
  // force's error then falls at the reference step's rate per unit of time whatever the CFL
  // target, and where max_dt or the viscous bound sets both steps w = 1. Tested:
  // FluidModule.TheReferenceCflSharesTheIncrementsByTheStepRatio.
  double carry_over_reference_cfl = 0;
};

class FluidModule final : public Module {
 public:
  // The solver, the markers and the forcing must outlive the module. Throws InputError on
  // time_scale_ms <= 0 (naming the field).
  FluidModule(fluid::FluidSolver& fluid, ibm::Markers& markers, ibm::DirectForcing& forcing,
              FluidModuleOptions options);

  const std::string& name() const override { return name_; }
  double time_ms() const override { return fluid_.time() * options_.time_scale_ms; }
  double max_step_ms() const override { return fluid_.stable_step() * options_.time_scale_ms; }
  void step(double dt_ms) override;
  void save() override {
    fluid_.save_state(saved_);
    saved_carried_ = forcing_.carried_force();
  }
  void restore() override {
    fluid_.restore_state(saved_);
    forcing_.set_carried_force(saved_carried_);
  }

  // Input: a deformable body's node positions and velocities (grid units, sizes = the body's
  // tiled nodes; Markers::set_nodes checks them).
  void set_body_nodes(int body, const std::vector<ibm::Vec3>& position, const std::vector<ibm::Vec3>& velocity);
  // Output: loads on every marker at the current state; bodies: only these (by index; empty:
  // all), the others 0 and not probed (ibm::compute_loads). Collective.
  ibm::MarkerLoads loads(const std::vector<bool>& bodies = {}) const;
  // The wall shear stress (eq 27) extrapolated to the wall at every marker
  // (ibm::wall_shear_stress: twice the loads' probes, for output times). Collective.
  ibm::WallShear wall_shear() const;
  // The forcing's report of the last step (slip before the forcing, total force on the fluid).
  const ibm::ForcingReport& last_forcing() const { return forcing_.last_report(); }

  fluid::FluidSolver& fluid() { return fluid_; }
  const ibm::Markers& markers() const { return markers_; }

 private:
  std::string name_ = "fluid";
  fluid::FluidSolver& fluid_;
  ibm::Markers& markers_;
  ibm::DirectForcing& forcing_;
  FluidModuleOptions options_;
  fluid::FluidSolver::State saved_;
  std::vector<ibm::Vec3> saved_carried_;  // the forcing's carried force (carry-over) at save()
  bool moved_ = false;  // a body's nodes changed since the last step
};

}  // namespace systole::coupling
