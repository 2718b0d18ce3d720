#pragma once
// The seed's rigid valvular plane (MODEL.md §4, eq 4): a fixed, grid-aligned, zero-thickness
// plate with openings, imposed by the direct forcing of Fadlun, Verzicco, Orlandi &
// Mohd-Yusof (2000, J. Comput. Phys. 161:35) at the first grid node outside the body. For
// each velocity component, in every grid column normal to the plane where the plate is
// present, the node x₁ nearest to the plane on each side gets
//     F(x₁) = (V* − û(x₁))/Δt,   V* = V_b + (û(x₂) − V_b) d₁/(d₁ + Δ)            (eq 4)
// with x₂ the next node away from the plane, d₁ = |x₁ − plane| and V_b = 0 (a fixed plate): the
// no-slip condition moved to x₁ by linear interpolation between the wall and x₂. A node exactly
// on the plane (d₁ = 0: the normal component when the plane is a face plane) gets V* = V_b.
// (ours: û(x₂), the predicted velocity, where the paper names uⁿ(x₂); both are first-order
// close, and û is what the fluid's body-force hook hands over.)
//
// Contract
// - The plane is normal to the axis `axis` (0 = x, 1 = y, 2 = z) at coordinate `position`
//   (grid units, inside the box, ≥ 2 cells off the z walls for axis = 2); `solid(a, b)` tells
//   whether the plate covers the point with in-plane coordinates (a, b) = the two other axes
//   in increasing order (x: (y, z); y: (x, z); z: (x, y)). The openings are where solid is
//   false; they are staircased on the grid (the method's nature).
// - Every rank forces only its own interior nodes; x₂ may be a z halo (valid in û): the result
//   is the same on any number of ranks.
// - Switched off (set_active(false)) it adds nothing: an opening that closes is a second
//   PlaneForcing covering it, switched on and off (the seed's vein ostia, MODEL.md §2).
#include <array>
#include <functional>
#include <memory>

#include "solver/ibm/transfer.h"

namespace systole::ibm {

struct RigidPlane {
  int axis = 2;
  double position = 0;
  std::function<bool(double, double)> solid;  // in-plane coordinates → plate present
};

struct PlaneForcingNodes;  // the forced nodes (plane_forcing.cc)

class PlaneForcing {
 public:
  // Throws InputError for an axis outside {0, 1, 2}, a position outside the box (or < 2 cells
  // off the z walls for axis 2) or a missing solid predicate.
  PlaneForcing(const grid::Slabs& slabs, RigidPlane plane);

  void set_active(bool active) { active_ = active; }
  bool active() const { return active_; }

  // Adds eq 4's forcing to f for a step dt, û with valid halos. uniform_force: a uniform force
  // density g the caller adds to f as well (a driving force): the nodes then see û + Δt g (as in
  // DirectForcing::apply). Returns Σ F ΔV_cell over the forced nodes of every rank (the force
  // on the fluid; the plate feels −it). Collective.
  Vec3 apply(double dt, const ConstVelocityView& u_hat, VelocityView f, const Vec3& uniform_force = Vec3::Zero()) const;

  // Number of forced nodes per component on this rank (diagnostics, tests).
  std::array<std::size_t, 3> forced_nodes() const;

 private:
  const grid::Slabs& slabs_;
  RigidPlane plane_;
  bool active_ = true;
  std::shared_ptr<const PlaneForcingNodes> nodes_;  // per component, built once
};

}  // namespace systole::ibm
