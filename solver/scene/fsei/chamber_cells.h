#pragma once
// The grid cells inside a heart chamber closed by the valvular plane (ours; scenes fsi/fsei use
// it for the kinetic energy of the chambers' blood, the seed's "kinetic energy in the heart").
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::scene {

// The cells (i, j, k), k in [k_begin, k_begin + k_count), whose centres ((i + ½) hx, (j + ½) hy,
// (k + ½) hz) mm lie inside the chamber bounded by the triangles `tri` at the positions x_mm and
// the plane z = plane_z_mm: a centre on the chamber's side (side = +1: z > plane_z_mm, the LV;
// -1: z < plane_z_mm, the LA) is inside when the ray from it away from the plane (along side · z)
// crosses the triangles an odd number of times (a crossing is where the ray's column meets a
// triangle's vertical projection; the columns are shifted by 1e-7 of a cell so that no column
// meets a shared edge or vertex exactly). Contract: the chamber's open rim lies in the plane and
// its surface is closed elsewhere. Returns mask[((k - k_begin) ny + j) nx + i], 1 inside.
std::vector<char> chamber_cells(const std::vector<geometry::Vec3>& x_mm, const std::vector<geometry::Tri>& tri,
                                double plane_z_mm, int side, int nx, int ny, int k_begin, int k_count, double hx_mm,
                                double hy_mm, double hz_mm);

// The cells of either chamber, the LV on side lv_side of the plane and the LA on the other (the
// union of the two chamber_cells masks, same layout): the cells of the chambers' blood.
std::vector<char> heart_chambers_cells(const std::vector<geometry::Vec3>& lv_x_mm, const std::vector<geometry::Tri>& lv_tri,
                                       const std::vector<geometry::Vec3>& la_x_mm, const std::vector<geometry::Tri>& la_tri,
                                       double plane_z_mm, int lv_side, int nx, int ny, int k_begin, int k_count,
                                       double hx_mm, double hy_mm, double hz_mm);

}  // namespace systole::scene
