// Import -> export -> import round trips (VTK, STL binary and ASCII, OBJ, XDMF/HDF5) and the
// JSON manifest that turns a user's surfaces into tagged bodies.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/geometry/diagnostics.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/mesh_io.h"
#include "solver/geometry/quality.h"

namespace systole::geometry {
namespace {

namespace fs = std::filesystem;

const LeftHeart& heart() {
  static const LeftHeart h = [] {
    auto s = config::default_scenario();
    s.geometry.target_edge_mm = 3;
    return build_left_heart(s.geometry, s.fluid);
  }();
  return h;
}

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / ("systole_geometry_io_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir / name;
}

void expect_identical(const TriMesh& a, const TriMesh& b) {
  ASSERT_EQ(a.node_count(), b.node_count());
  ASSERT_EQ(a.triangle_count(), b.triangle_count());
  EXPECT_EQ(a.position_mm, b.position_mm);
  EXPECT_EQ(a.tri, b.tri);
  EXPECT_EQ(a.region, b.region);
  EXPECT_EQ(a.tissue, b.tissue);
  EXPECT_EQ(a.thickness_mm, b.thickness_mm);
  EXPECT_EQ(a.fibre, b.fibre);
}

TEST(MeshIo, VtkRoundTripKeepsEverything) {
  for (const auto& b : heart().bodies) {
    const fs::path p = scratch(b.name + ".vtk");
    write_vtk(p, b);
    const TriMesh back = read_vtk(p);
    expect_identical(b, back);
    EXPECT_EQ(back.name, b.name);
    const fs::path pb = scratch(b.name + "_binary.vtk");
    write_vtk(pb, b, /*binary=*/true);
    expect_identical(b, read_vtk(pb));
  }
}

TEST(MeshIo, Hdf5RoundTripKeepsEverythingAndWritesXdmf) {
  const auto files = write_xdmf_hdf5(scratch("heart"), heart().body_pointers());
  ASSERT_EQ(files.size(), 2u);
  const auto back = read_hdf5(files[0]);
  ASSERT_EQ(back.size(), heart().bodies.size());
  for (std::size_t i = 0; i < back.size(); ++i) {
    EXPECT_EQ(back[i].name, heart().bodies[i].name);
    EXPECT_EQ(back[i].kind, heart().bodies[i].kind);
    expect_identical(heart().bodies[i], back[i]);
  }
  std::ifstream x(files[1]);
  const std::string xml((std::istreambuf_iterator<char>(x)), std::istreambuf_iterator<char>());
  EXPECT_NE(xml.find("TopologyType=\"Triangle\""), std::string::npos);
  EXPECT_NE(xml.find("heart.h5:/lv/fibre"), std::string::npos);
  EXPECT_NE(xml.find("Name=\"region\""), std::string::npos);
}

TEST(MeshIo, StlBinaryAndAsciiRoundTrip) {
  const TriMesh& lv = heart().body(kLvBody);
  const fs::path bin = scratch("lv_bin.stl");
  write_stl_binary(bin, lv);
  const TriMesh b = read_stl(bin);
  EXPECT_EQ(b.triangle_count(), lv.triangle_count());
  EXPECT_EQ(b.node_count(), lv.node_count());  // shared corners merged back
  EXPECT_NEAR(cavity_volume_ml(b, heart().plane.z_mm), 125.0, 1e-3);  // float precision
  // ASCII STL written by hand (a square of two facets).
  const fs::path asc = scratch("square.stl");
  std::ofstream(asc) << "solid sq\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\n"
                        "endloop\nendfacet\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 1 0\n"
                        "vertex 0 1 0\nendloop\nendfacet\nendsolid sq\n";
  const TriMesh s = read_stl(asc);
  EXPECT_EQ(s.triangle_count(), 2u);
  EXPECT_EQ(s.node_count(), 4u);
}

TEST(MeshIo, ObjRoundTrip) {
  const TriMesh& la = heart().body(kLaBody);
  const fs::path p = scratch("la.obj");
  write_obj(p, la);
  const TriMesh back = read_obj(p);
  EXPECT_EQ(back.position_mm, la.position_mm);
  EXPECT_EQ(back.tri, la.tri);
}

TEST(MeshIo, ReadErrorsNameTheFileAndProblem) {
  const fs::path bad = scratch("bad.obj");
  std::ofstream(bad) << "v 0 0 0\nv 1 0 0\nf 1 2 7\n";
  try {
    read_obj(bad);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.obj"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(read_mesh(scratch("x.ply")), InputError);
  EXPECT_THROW(read_vtk(scratch("missing.vtk")), InputError);
}

TEST(MeshIo, ManifestMakesAUsersHeartUsable) {
  // A user's LV and LA as plain STL (no tags), described by a manifest.
  const LeftHeart& h = heart();
  write_stl_binary(scratch("user_lv.stl"), h.body(kLvBody));
  write_obj(scratch("user_la.obj"), h.body(kLaBody));
  const Vec3 his = h.plane.centre_mm + Vec3(25, 0, 9);
  nlohmann::json m = {
      {"valvular_plane_z_mm", h.plane.z_mm},
      {"bodies",
       {{{"name", "lv"}, {"file", "user_lv.stl"}, {"kind", "chamber"}, {"tissue", "lv_myocardium"},
         {"thickness_mm", 8},
         {"fibre", {{"rule", "helix"}, {"angle_deg", 45}, {"axis_point_mm", {h.plane.centre_mm.x(), h.plane.centre_mm.y(), 0}}, {"axis", {0, 0, 1}}}},
         {"regions", {{{"name", "anchor"}, {"near_plane_mm", 1e-3}},
                      {{"name", "his_bundle"}, {"sphere", {{"centre_mm", {his.x(), his.y(), his.z()}}, {"radius_mm", 5}}}}}}},
        {{"name", "la"}, {"file", "user_la.obj"}, {"kind", "chamber"}, {"tissue", "la_myocardium"},
         {"thickness_mm", 4}, {"fibre", {{"rule", "vertical"}}},
         {"regions", {{{"name", "anchor"}, {"near_plane_mm", 1e-6}}}}}}}};
  std::ofstream(scratch("heart.json")) << m.dump(2);
  const ImportedHeart user = load_manifest(scratch("heart.json"));
  ASSERT_EQ(user.bodies.size(), 2u);
  CheckOptions o;
  o.plane_z_mm = user.plane_z_mm;
  o.plane_tolerance_mm = 1e-3;
  o.degenerate_min_angle_deg = 0.1;
  for (const auto& b : user.bodies) {
    const auto issues = check_body(b, o);
    EXPECT_TRUE(issues.empty()) << b.name << ": " << (issues.empty() ? "" : issues[0].message);
  }
  EXPECT_NEAR(cavity_volume_ml(user.bodies[0], user.plane_z_mm), 125.0, 1e-3);
  EXPECT_NEAR(cavity_volume_ml(user.bodies[1], user.plane_z_mm), 40.0, 1e-9);
  std::size_t his_nodes = 0;
  for (auto r : user.bodies[0].region) his_nodes += (r & kHisBundle) != 0;
  EXPECT_GT(his_nodes, 3u);
  // The helix rule gives the same fibres as the generator.
  for (std::size_t t = 0; t < user.bodies[0].triangle_count(); t += 50)
    EXPECT_GT(user.bodies[0].fibre[t].dot(h.body(kLvBody).fibre[t]), 0.999);
  // The imported surfaces go through the same intersection check as the procedural ones.
  EXPECT_TRUE(check_intersections({&user.bodies[0], &user.bodies[1]}).empty());
}

TEST(MeshIo, ManifestErrorsNameTheEntry) {
  write_obj(scratch("m_la.obj"), heart().body(kLaBody));
  nlohmann::json m = {{"valvular_plane_z_mm", 0},
                      {"bodies", {{{"file", "m_la.obj"}, {"tissue", "atrium"}, {"thickness_mm", 4}}}}};
  std::ofstream(scratch("bad.json")) << m.dump();
  try {
    load_manifest(scratch("bad.json"));
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown tissue 'atrium'; known: valvular_plane"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace systole::geometry
