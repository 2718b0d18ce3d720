#pragma once
// A membrane pre-stress found by solving for the spring rest lengths (ours).
//
// The seed starts its aorta "pretensioned by an external force providing a ground pressure of
// 60 mmHg" (MODEL.md §1). An outer load equal to the blood's pressure leaves the wall without
// tension, and an untensioned tube under a net outer pressure buckles (the immersed aorta did).
// Here the wall itself carries the pressure: the rest lengths l0 of the springs are shortened so
// that the shell, at its built (stress-free mesh) positions, is in equilibrium with the given
// nodal loads (an inner pressure). This is the force-density idea of tension structures (Schek
// 1974) turned around: the shape is given and the edge forces are solved for.
//
// Contract of membrane_prestress(model, load):
//  - x = model.positions_mm(); unknowns: a constant in-plane membrane tension N_T (2 x 2, mN/mm)
//    per triangle; a triangle's stress is carried by its three springs exactly, F_e += -l_e A_T
//    g_i^T N_T g_j for its edge (i, j) (g the gradients of the barycentric functions: the edge
//    forces give its nodes -A_T N_T g_k, those of a constant-stress triangle);
//  - equations: at every free node, sum of the spring forces + load = 0, in the least-squares
//    sense, with the jump of the 3-D tensor N across every interior edge penalised (weight
//    `smoothing` relative to the equilibrium's mean l^2) and a tiny Tikhonov term (`regularization`
//    of the mean diagonal). The spring forces of an exact equilibrium are (nearly) unique, and on a
//    mesh with near-mechanisms wild: on the heart's aorta strains of ±80 % alternate along mesh
//    lines. The smoothing trades a residual for a smooth stress (ours): with the default 1e-2 the
//    aorta keeps 14 % of its load unbalanced (its wall moves a little at t = 0 to carry it) with
//    strains of -19 ... +48 %; a small smoothing (1e-9) gives the exact equilibrium
//    (tests/structure/prestress_test.cc);
//  - each F_e becomes a rest length by inverting the spring law at the current length:
//    tau(eps) C / l = F, eps = 1 - l0/l, by bisection on [0, 1) ([-1, 0] for a compressive F: an
//    obtuse triangle's long edge carries compression even in isotropic tension); a force beyond
//    the law's stress at the strain limit throws InputError naming the body, the worst spring and
//    how many; below it the rest lengths do not depend on the limit (bitwise);
//  - bending hinges are not touched: at the stress-free positions they exert no force;
//  - residual_relative is |sum of the realised spring forces + load| over the free nodes,
//    relative to |load|: what the pre-stressed model will see at t = 0 (bending aside).
#include <cstdint>
#include <vector>

#include "solver/structure/shell.h"

namespace systole::structure {

struct PrestressOptions {
  double smoothing = 1e-2;        // weight of the stress jumps between neighbouring triangles (ours)
  double regularization = 1e-12;  // Tikhonov, relative to the mean diagonal
  bool compression = true;        // false: springs whose force comes out compressive are left
                                  // slack (rest length = length) instead of pre-compressed (ours)
};

struct Prestress {
  std::vector<double> rest_length_mm;  // per spring, in model.springs() order
  std::vector<double> force_mn;        // realised axial force per spring (tension > 0)
  std::vector<double> membrane_tension_mn_per_mm;  // per triangle: the larger principal tension
  double residual_relative = 0;        // |sum F_e u_e + load| / |load| over free nodes
  double max_strain = 0, min_strain = 0, mean_strain = 0;  // eps = 1 - l0/l over the pre-stressed springs
  std::int32_t max_strain_spring = -1;
  int slack_springs = 0;               // springs with no force (rest length = length)
  int compressed_springs = 0;          // springs pre-compressed (rest length > length)
};

Prestress membrane_prestress(const ShellModel& model, const std::vector<Vec3>& load_mn,
                             const PrestressOptions& options = {});

// Nodal forces (mN) of a uniform pressure p (kPa) on the triangles of `mesh` at positions x,
// p A n / 3 per node of each triangle along its normal n = (b - a) x (c - a) / |.| (for the
// heart's bodies, whose normals point into the cavity, a positive p pulls the wall inwards;
// pass -p for an inner pressure). Triangles whose nodes all carry a region bit in `skip_region`
// carry none.
std::vector<Vec3> pressure_nodal_forces(const geometry::TriMesh& mesh, const std::vector<Vec3>& x_mm,
                                        double pressure_kpa, std::uint32_t skip_region = 0);

}  // namespace systole::structure
