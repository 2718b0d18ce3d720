#pragma once
// Direct forcing (MODEL.md §4, eq 3, 8): at each active marker F_b = (V_b − û(X_b))/Δt, spread
// to the grid (eq 6–7) and added to the fluid's body force so that u* = û + Δt f carries the
// body's velocity at the markers before the projection. Optional multi-direct forcing
// (ours; Luo et al. 2007, Wang, Fan & Luo 2008 J. Comput. Phys. 227:6226): the interpolation and
// correction repeated on u* = û + Δt f, F accumulating the corrections, to reduce the slip that
// overlapping supports leave after one pass.
//
// The fluid is reached only through its body-force hook (scene/ wires
// FluidSolver::set_body_force to apply()): this module does not depend on solver/fluid.
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/core/state_archive.h"
#include "solver/ibm/transfer.h"

namespace systole::ibm {

struct ForcingParameters {
  int iterations = 1;  // forcing passes per step, [1, 20]; 1 = the seed's single pass
  // Carry the force over (ours): each step starts from the previous step's Lagrangian force
  // F^{n−1} (spread, and û + Δt f re-interpolated) and adds the direct-forcing correction,
  // F^n = F^{n−1} + (V_b − (û + Δt f^{n−1})(X_b))/Δt: the integral part of the feedback forcing
  // of Goldstein, Handler & Sirovich (1993, J. Comput. Phys. 105:354) with gain 1/Δt. A single
  // pass removes only a fraction of the slip (overlapping supports), so under a steady load
  // (the pressure jump across a thin plate) the seed's forcing leaves a steady slip ∝ Δt ∇p —
  // a leak through the plate; carried over, the slip of a steady load goes to 0. Costs one
  // more interpolation and spreading per step (markers switched on start from F = 0).
  bool carry_over = false;
  // With carry_over: the share β of F^{n−1} carried, (0, 1] (ours). Below 1 the integral leaks:
  // a slip that the forcing cannot remove (markers of two bodies with different velocities in
  // one support) no longer winds the force up without bound (F ≤ correction / (1 − β)), at the
  // price of a steady slip (1 − β) times the one without carry-over.
  double carry_over_factor = 1.0;
  // With carry_over: the share w of this step's corrections that the carried force keeps, (0, 1]
  // (ours): the next step starts from β (F_start + w (F − F_start)), F_start the force this step
  // started from; the force applied this step is F whatever w. Once the passes' slip follows the
  // carried force's error e (slip ≈ −Δt e / λ, λ the share of the slip the passes remove), e falls
  // by 1 − w per step: at the rate w/Δt per unit of time, so w = Δt/Δt_ref keeps the rate of the
  // step Δt_ref at a smaller step (in the immersed heart at CFL 0.2 three passes ran away where one
  // pass completed). A steady load reaches the same carried force and slip as with
  // w = 1, only more slowly (tests/ibm/forcing_test.cc).
  double carry_over_increment_share = 1.0;
  // With carry_over: markers within this × h of a marker of another body carry nothing over
  // (ours), [0, 4]; 0: every marker carries. Anti-windup: where two bodies' supports overlap
  // (leaflets meeting at a commissure, a leaflet at its annulus) their targets can conflict, the
  // slip there cannot be removed, and the carried force would grow step after step. Rigid
  // bodies count too: leaving the valvular plane out, the heart's cusps crumpled at 16.6 ms.
  double carry_over_exclusion_cells = 0.0;
  // With the exclusion: false keeps the carry-over of rigid bodies' markers next to other bodies
  // (ours; the other bodies' markers next to them still carry none). A rigid body's target is
  // its own prescribed motion, which its anchored neighbours share; tried with MLS, a cusp
  // crumpled next to the plane.
  bool carry_over_exclusion_rigid = true;
  // With carry_over: a pair of markers of which one is a rigid body's excludes within
  // max(this, carry_over_exclusion_cells) × h (ours), [0, 4]; 0: as any pair. A wider ring where a
  // deformable wall meets the rigid valvular plane: there the wall's motion and the plane's rest
  // conflict over more of the kernel's support than between two moving bodies (a stiff LA wound up
  // 1.1-2.4 mm, 0.7-1.6 h, below the plane at 180 bpm).
  double carry_over_exclusion_rigid_cells = 0.0;
  // With carry_over: a pair of a rigid body's marker and a one-sided deformable body's (a wall,
  // blood on one side: the chambers, the aorta) excludes within max(this,
  // carry_over_exclusion_rigid_cells, carry_over_exclusion_cells) × h (ours), [0, 4]; 0: as
  // the other rigid pairs. The wall-only ring: a two-sided leaflet's base keeps its carried force
  // next to the plane; with the ring on every body the closed aortic valve passed 1.22 ml back
  // against 0.39 ml with it on the walls only (measured at `coarse`, 70 bpm).
  double carry_over_exclusion_rigid_wall_cells = 0.0;
  // Stencils are rebuilt only for bodies with a marker moved more than this × h since their
  // last build (ours; Transfer::set_rebuild_tolerance), in [0, 0.5]; 0: after any move.
  double rebuild_tolerance_cells = 0;
  // The markers' interpolation and spreading weights (TransferKernel): the seed's MLS, or the
  // divergence-free composite B-splines (ours), whose interpolated velocity has no flux through a
  // closed wall: the forcing can no longer hold U = V at every marker while the enclosed volume
  // changes (the IB's volume leak; tested in
  // FsiSphere.TheDivergenceFreeKernelHoldsTheVolumeTheMlsKernelLoses).
  TransferKernel kernel = TransferKernel::mls;
};
void validate(const ForcingParameters& p);

struct SlipStats {
  double rms = 0, max = 0;  // over active markers, |V_b − u(X_b)|
  std::size_t markers = 0;
};

struct ForcingReport {
  SlipStats slip_before;        // of û (what the forcing corrects); the slip after the last
                                // pass is not measured (it would cost an interpolation)
  Vec3 total_force = Vec3::Zero();  // Σ_b F_b ΔV_b: the force on the fluid (the body feels −it)
  int iterations = 0;
};

class DirectForcing {
 public:
  // The markers are referenced: call markers_moved() after they moved. Validates parameters.
  DirectForcing(const grid::Slabs& slabs, const Markers& markers, ForcingParameters parameters);

  // Adds the forcing of eq 3 to f (this rank's interior faces) for the step of size dt, given
  // û with valid halos. Collective. Returns the report of this step. uniform_force: a uniform
  // force density g the caller adds to f as well (a driving force); its velocity Δt g is added
  // to the interpolated û (exact: Σφ = 1), so the markers see û + Δt g. Add g to f after apply().
  // increment_share_factor, in (0, 1] (InputError otherwise): multiplies
  // carry_over_increment_share for this step only (the caller's step-aware share:
  // coupling::FluidModuleOptions::carry_over_reference_cfl); 1 leaves the parameter as it is.
  const ForcingReport& apply(double dt, const ConstVelocityView& u_hat, VelocityView f,
                             const Vec3& uniform_force = Vec3::Zero(), double increment_share_factor = 1.0);
  void markers_moved() {
    transfer_.rebuild();
    update_carry_mask();
  }
  // Markers excluded from the carry-over (carry_over_exclusion_cells) at the last update.
  std::size_t carry_over_excluded() const { return excluded_; }
  // Whether marker (an index of the markers, < their count; std::out_of_range otherwise) carried
  // its force over at the last update: true for all when the carry-over excludes none.
  bool carries_over(std::size_t marker) const;
  // The exclusion radii in cells (h) the carry mask applies, by pair: any two deformable bodies;
  // a rigid body with a two-sided one (a leaflet) or with another rigid body; a rigid body with a
  // one-sided one (a wall). Each is the widest of the parameters that apply to the pair.
  struct ExclusionRadii {
    double pair_cells = 0, rigid_cells = 0, rigid_wall_cells = 0;
  };
  ExclusionRadii carry_over_exclusion_radii() const;

  // Slip of a velocity field (halos valid) at the active markers. Collective.
  SlipStats slip(const ConstVelocityView& u) const;
  // F_b of the last apply() (per marker, force density; 0 for inactive markers).
  const std::vector<Vec3>& force_density() const { return force_; }
  const ForcingReport& last_report() const { return report_; }
  // The carried force F^{n−1} (carry_over): state that the next step starts from, empty before
  // the first step. A strong coupling's repeated interval and a checkpoint save and restore it
  // with the fluid (else a restored run would not repeat bitwise). set_carried_force takes an
  // empty vector or one value per marker (std::invalid_argument otherwise).
  const std::vector<Vec3>& carried_force() const { return previous_; }
  void set_carried_force(std::vector<Vec3> force);
  // The carried force in a checkpoint, under prefix + "carried_force" (written only when there is
  // one; a missing entry restores none). Identical on every rank (global marker forces).
  void export_state(StateArchive& archive, const std::string& prefix) const;
  void import_state(const StateArchive& archive, const std::string& prefix);
  const Transfer& transfer() const { return transfer_; }
  const ForcingParameters& parameters() const { return par_; }

 private:
  SlipStats slip_of(const std::vector<Vec3>& interpolated) const;
  void update_carry_mask();  // carries_ from the markers' positions (carry_over_exclusion_cells)
  const grid::Slabs& slabs_;
  const Markers& markers_;
  ForcingParameters par_;
  Transfer transfer_;
  std::vector<Vec3> force_, increment_, previous_, interpolated_;
  std::vector<Vec3> start_;  // the force a step started from (carry_over_increment_share < 1)
  ForcingReport report_;
  std::vector<char> carries_;  // per marker: 1 = its force is carried over (empty: all)
  std::size_t excluded_ = 0;
  // update_carry_mask's buffers (cells' starts and bodies, the markers' cells and sorted order)
  std::vector<std::uint32_t> mask_start_, mask_order_, mask_cell_of_, mask_fill_;
  std::vector<std::uint64_t> mask_bodies_;
  // Work velocity û + Δt f of the multi-direct passes (allocated when iterations > 1 or with
  // the carry-over).
  std::unique_ptr<grid::XFaceField> work_u_;
  std::unique_ptr<grid::YFaceField> work_v_;
  std::unique_ptr<grid::ZFaceField> work_w_;
};

}  // namespace systole::ibm
