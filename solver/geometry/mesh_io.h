#pragma once
// Mesh import and export.
// - Import: STL (ASCII and binary; duplicate vertices merged exactly), OBJ (v / f, polygons
//   fanned, negative indices), legacy VTK POLYDATA (ASCII or BINARY; POINTS + POLYGONS /
//   TRIANGLE_STRIPS, and the fields written by write_vtk: region, tissue, thickness_mm, fibre).
// - A JSON manifest assigns kind, tissue, thickness, fibre rule and regions to imported
//   surfaces, so a user's own left heart can replace the procedural one (load_manifest).
// - Export: legacy VTK (one file per body, with every field) and XDMF + HDF5 (all bodies in
//   one file pair, opens in ParaView).
// All functions throw InputError naming the file and the problem (line numbers for text).
#include <filesystem>
#include <string>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

TriMesh read_stl(const std::filesystem::path& path);
TriMesh read_obj(const std::filesystem::path& path);
TriMesh read_vtk(const std::filesystem::path& path);
// By extension: .stl, .obj, .vtk.
TriMesh read_mesh(const std::filesystem::path& path);

// Legacy VTK POLYDATA, ASCII (default) or BINARY (big-endian), with every field.
void write_vtk(const std::filesystem::path& path, const TriMesh& mesh, bool binary = false);
void write_stl_binary(const std::filesystem::path& path, const TriMesh& mesh);
void write_obj(const std::filesystem::path& path, const TriMesh& mesh);

// Writes <base>.h5 and <base>.xdmf: one grid per body with points, triangles, node regions,
// triangle tissue, thickness and fibre. Returns the two paths.
std::vector<std::filesystem::path> write_xdmf_hdf5(const std::filesystem::path& base,
                                                   const std::vector<const TriMesh*>& bodies);
// Reads back what write_xdmf_hdf5 wrote (the .h5 file).
std::vector<TriMesh> read_hdf5(const std::filesystem::path& h5_path);

// A manifest (JSON) describing a user's heart:
// {
//   "valvular_plane_z_mm": 40.0,
//   "bodies": [
//     { "name": "lv", "file": "lv.stl", "kind": "chamber", "tissue": "lv_myocardium",
//       "thickness_mm": 8, "scale_to_mm": 1.0, "flip_normals": false,
//       "fibre": { "rule": "helix", "angle_deg": 45, "axis_point_mm": [x,y,z], "axis": [0,0,1] },
//       "regions": [ { "name": "anchor", "near_plane_mm": 0.01 },
//                    { "name": "his_bundle", "sphere": { "centre_mm": [x,y,z], "radius_mm": 5 } },
//                    { "name": "lv_apex", "nodes": [123] } ] } ] }
// Fibre rules: "keep" (from the file, VTK/HDF5 only), "helix" (angle from the circumferential
// direction about the axis, rising towards -axis), "vertical" (projection of -axis),
// "circumferential" (about the axis), "constant" ("direction": [x,y,z] projected).
// Relative file names are resolved against the manifest's folder.
struct ImportedHeart {
  double plane_z_mm = 0;
  std::vector<TriMesh> bodies;
};
ImportedHeart load_manifest(const std::filesystem::path& manifest_path);

}  // namespace systole::geometry
