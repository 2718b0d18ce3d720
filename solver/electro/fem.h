#pragma once
// P1 finite elements on ElectroMesh (triangles in 3-D or tetrahedra), one assembly path.
//
// Contract
// - Lengths are converted from mm to cm here (kCmPerMm): areas in cm^2, volumes in cm^3, so a
//   stiffness assembled with conductivities in mS/cm acts on potentials in mV and yields
//   currents in uA (per cm of wall thickness for surfaces: the surface model is a thin wall
//   with through-thickness-constant fields, ours, as the seed's surface bidomain).
// - Matrices are assembled ONCE, in the reference configuration (ours, documented choice: the
//   seed's electrophysiology runs on the undeformed walls; mechano-electric feedback through
//   the changing metric is neglected).
// - Mass: consistent P1 mass, M_ab = |K| (1 + delta_ab) / ((d+1)(d+2)).
// - Stiffness: K_ab = |K| grad(phi_a)^T Sigma grad(phi_b), Sigma = s_c I + (s_f - s_c) f f^T.
#include <Eigen/Sparse>

#include "solver/electro/mesh.h"

namespace systole::electro {

inline constexpr double kCmPerMm = 0.1;

using SparseMatrix = Eigen::SparseMatrix<double>;

// Conductivity along and across the fibre, mS/cm. Both must be > 0 (InputError otherwise).
struct Conductivity {
  double fibre_ms_per_cm;
  double cross_ms_per_cm;
};

// Measure of each cell (cm^2 or cm^3). Throws InputError for a degenerate cell.
std::vector<double> cell_measures_cm(const ElectroMesh& mesh);
SparseMatrix assemble_mass(const ElectroMesh& mesh);
// Row sums of the consistent mass (the lumped mass; a node's share of the area / volume).
Eigen::VectorXd lumped_mass(const ElectroMesh& mesh);
// cell_scale (optional, one factor > 0 per cell): sigma of cell c is multiplied by cell_scale[c]
// (per-domain conductivity scaling, e.g. the atrial scale of the scene; ours).
SparseMatrix assemble_stiffness(const ElectroMesh& mesh, const Conductivity& sigma,
                                const std::vector<double>& cell_scale = {});

}  // namespace systole::electro
