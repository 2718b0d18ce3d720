#pragma once
// The electrophysiology mesh: P1 simplices, either triangles embedded in 3-D (the chamber
// walls, from geometry::TriMesh) or tetrahedra (slabs for verification). One struct, one
// assembly path (fem.h): a triangle is a cell whose 4th node index is -1.
//
// Contract
// - position_mm: node positions in millimetres (the geometry module's unit). The FEM converts
//   to centimetres explicitly (fem.h), because conductivities are in mS/cm and chi in 1/cm.
// - fibre: one unit vector per cell (tangent to the triangle for surfaces). Conductivity
//   tensors are sigma_c I + (sigma_f - sigma_c) f f^T: on a surface the gradients of P1 fields
//   lie in the cell plane, so the cross-fibre value acts along the in-plane normal to f; in a
//   tetrahedron the cross-fibre plane is transversely isotropic (ours: no sheet direction).
// - node_region: geometry::Region bits per node (stimulus sites, apex...).
// - node_domain: which cell model serves the node (index into the scene's domain list, e.g.
//   0 = LV, 1 = LA). Domains may be disconnected (LV and LA walls are separate surfaces).
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "solver/geometry/tri_mesh.h"

namespace systole::electro {

using Vec3 = Eigen::Vector3d;

struct ElectroMesh {
  int cell_dim = 2;  // 2: triangles, 3: tetrahedra
  std::vector<Vec3> position_mm;
  std::vector<std::array<std::int32_t, 4>> cell;  // triangles: cell[i][3] == -1
  std::vector<Vec3> fibre;                        // per cell, unit
  std::vector<std::uint32_t> node_region;
  std::vector<std::uint8_t> node_domain;
  std::vector<std::string> domain_names;  // e.g. {"lv", "la"}
  // from_surfaces only (empty otherwise): {body index, node index in that body} of every node,
  // so fields can be mapped back to the surface meshes (e.g. tension to the structure).
  std::vector<std::array<std::int32_t, 2>> source_node;

  std::size_t node_count() const { return position_mm.size(); }
  std::size_t cell_count() const { return cell.size(); }
  int nodes_per_cell() const { return cell_dim + 1; }
  // Throws InputError on inconsistent sizes, bad indices, non-unit fibres or degenerate cells.
  void check() const;
  // Connected component of each node (through shared cells); count = max + 1.
  std::vector<std::int32_t> components() const;
};

// A flat rectangular sheet in z = 0: [0, size_x] x [0, size_y] mm, nodes every spacing_mm
// (rounded so the sizes are met exactly), each square split into two triangles with the
// diagonal alternating in a checkerboard (ours: no preferred direction). Fibres in-plane at
// fibre_angle_deg from +x. One domain "sheet".
ElectroMesh make_sheet(double size_x_mm, double size_y_mm, double spacing_mm, double fibre_angle_deg);

// A box slab [0, sx] x [0, sy] x [0, sz] mm of tetrahedra: a structured hexahedral grid with
// spacing ~spacing_mm, each cube split into 6 tetrahedra around its main diagonal (Kuhn split,
// conforming). Fibres at fibre_angle_deg from +x in the x-y plane. One domain "slab".
ElectroMesh make_slab(double sx_mm, double sy_mm, double sz_mm, double spacing_mm, double fibre_angle_deg);

// The walls of the given surface bodies (e.g. LV and LA of the procedural heart) as one mesh;
// body k becomes domain k, named after the body. Only triangles of myocardial tissue
// (kLvMyocardium, kLaMyocardium) are kept: the virtual pulmonary-vein caps and the rigid
// plane carry no excitable tissue (ours); nodes used by no kept triangle are dropped and the
// rest renumbered. Fibres and region tags are taken over.
ElectroMesh from_surfaces(const std::vector<const geometry::TriMesh*>& bodies);

}  // namespace systole::electro
