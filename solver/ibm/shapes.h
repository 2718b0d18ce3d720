#pragma once
// Simple bodies for the immersed-boundary verification scenes (ours): a sphere, a straight
// tube and a square plate with a circular hole, as geometry::TriMesh in millimetres with the
// TriMesh orientation contract (tri_mesh.h). Not heart geometry: solver/geometry makes that.
#include "solver/geometry/tri_mesh.h"

namespace systole::ibm {

// Icosphere: the icosahedron subdivided `subdivisions` times (20·4^s triangles), nodes on the
// sphere; normals point outward (the blood is outside). Tissue: valvular plane (rigid).
geometry::TriMesh sphere_mesh(const Eigen::Vector3d& centre_mm, double radius_mm, int subdivisions);

// A tube of radius radius_mm along x from x0_mm to x0_mm + length_mm, axis at (y, z) =
// (axis_y_mm, axis_z_mm), with n_axial × n_around quads split in two; normals point into the
// lumen (the blood is inside, the vessel convention). Open at both ends.
geometry::TriMesh tube_mesh(double x0_mm, double length_mm, double axis_y_mm, double axis_z_mm, double radius_mm,
                            int n_axial, int n_around);

// The square plate [x0, x0+side]×[y0, y0+side] at z = z_mm with a circular hole of radius
// hole_radius_mm at its centre: n_radial rings from the hole to the square edge, n_around
// nodes per ring. Normal +z (the valvular-plane convention: into the LV). Kind rigid.
geometry::TriMesh plate_with_hole_mesh(double x0_mm, double y0_mm, double side_mm, double z_mm, double hole_radius_mm,
                                       int n_radial, int n_around);

// The rectangle y ∈ [y0, y0+ly], z ∈ [z0, z0+lz] in the plane x = x_mm, ny × nz quads split in
// two, normal +x, and a circular opening of radius hole_radius_mm centred at (yc, zc): the
// plate keeps the triangles whose centroid lies outside the circle (part = plate), the cover
// the ones inside (part = cover), so plate and cover tile the rectangle exactly (the rim is
// staircased at the quad size, like eq 4's on the grid). The orifice plate of the scene's
// orifice_plate case and the cover switched on and off to close the opening.
enum class PlatePart { plate, cover };
geometry::TriMesh perforated_plate_x_mesh(double x_mm, double y0_mm, double ly_mm, double z0_mm, double lz_mm,
                                          double yc_mm, double zc_mm, double hole_radius_mm, int ny, int nz,
                                          PlatePart part);

// A full rectangle [x0, x0+lx]×[y0, y0+ly] at z = z_mm, nx × ny quads split in two, normal +z:
// a rigid plane spanning a periodic box (the valvular plane without its orifices).
geometry::TriMesh plate_mesh(double x0_mm, double y0_mm, double lx_mm, double ly_mm, double z_mm, int nx, int ny);

}  // namespace systole::ibm
