#pragma once
// Geometry diagnostics reused by later modules (structure, electro, diagnostics):
// cavity volume of a chamber closed by the valvular plane, areas, centroids, apex-base axis.
// All exact for the triangulated surface (no quadrature error): the divergence theorem with
// a field that vanishes on the valvular plane, so the flat closing cap contributes nothing.
#include <optional>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

// Volume (ml) enclosed by `mesh` and the plane z = plane_z_mm, for a chamber whose open
// boundary lies in that plane and whose normals point into the cavity:
//   V = -sum_T  integral_T (z - z_p) n_z dA   (field F = (0, 0, z - z_p), div F = 1).
// Positive for a correctly oriented chamber; negative if the normals point outwards.
double cavity_volume_ml(const TriMesh& mesh, double plane_z_mm);

// Centroid (mm) of that same closed cavity (exact: quadratic integrands, edge-midpoint rule).
Vec3 cavity_centroid_mm(const TriMesh& mesh, double plane_z_mm);

// Surface area (mm^2), optionally of one tissue only.
double surface_area_mm2(const TriMesh& mesh, std::optional<Tissue> tissue = std::nullopt);

// Area-weighted centroid of the surface (mm).
Vec3 surface_centroid_mm(const TriMesh& mesh);

struct ApexBaseAxis {
  Vec3 base_centre_mm;  // centroid of the base (open boundary) polygon in the valvular plane
  Vec3 apex_mm;         // the node tagged kLvApex, else the node farthest from the base centre
  Vec3 direction;       // unit vector base -> apex
  double length_mm;
};
// For a chamber closed by the valvular plane (the LV). Throws std::invalid_argument if the
// mesh has no boundary loop.
ApexBaseAxis apex_base_axis(const TriMesh& mesh);

}  // namespace systole::geometry
