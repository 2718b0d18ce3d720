#pragma once
// Simple bodies for verification and the mechanics scene (mm): a closed icosphere and a flat
// equilateral sheet. Both are ordinary geometry::TriMesh bodies (tissue, thickness, fibre).
#include "solver/geometry/tri_mesh.h"

namespace systole::structure {

// Icosahedron subdivided `level` times (each triangle into 4, new nodes projected on the
// sphere): 10 * 4^level + 2 nodes. Normals point into the cavity (the chamber convention).
// Fibres: azimuthal (e_z x r, projected on each triangle) when azimuthal_fibres, else none
// (isotropic springs). Kind kChamber, no anchors.
geometry::TriMesh icosphere(double radius_mm, int level, double thickness_mm, geometry::Tissue tissue,
                            bool azimuthal_fibres);

// Flat sheet in z = 0 of equilateral triangles with edge `edge_mm`, rows along x:
// nx nodes per row (x spacing edge_mm, odd rows shifted by edge/2), ny rows (spacing
// edge sqrt(3)/2). Normals +z. Fibres along `fibre` (projected in-plane; zero: none).
// Kind kLeaflet, no anchors.
geometry::TriMesh flat_sheet(int nx, int ny, double edge_mm, double thickness_mm, geometry::Tissue tissue,
                             const geometry::Vec3& fibre);

}  // namespace systole::structure
