// systole-geometry SCENARIO.json --out DIR [--set path=value ...] [--png FILE] [--markers]
//
// Builds the procedural left heart of a scenario's geometry variant and writes:
//   DIR/<body>.vtk           one legacy VTK file per body (regions, tissue, thickness, fibre)
//   DIR/heart.h5, heart.xdmf all bodies for ParaView
//   DIR/markers.h5/.xdmf     the quadratically tiled marker meshes (with --markers)
//   DIR/summary.json         volumes, areas, counts, quality, layout, tiling levels
// The scenario's "scene" is ignored (set to "lumped" before parsing, because parse_scenario
// accepts only implemented scenes): this command reads only geometry and fluid parameters.
#include <filesystem>
#include <fstream>
#include <iostream>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/geometry/left_heart.h"
#include "solver/geometry/mesh_io.h"
#include "solver/geometry/summary.h"
#include "solver/geometry/tiling.h"
#include "solver/geometry/tools/render.h"

namespace fs = std::filesystem;
using namespace systole;
using namespace systole::geometry;

int main(int argc, char** argv) {
  CLI::App app{"Build the procedural left heart of a scenario and export it"};
  std::string scenario_path, out_dir, png_path;
  std::vector<std::string> overrides;
  bool markers = false;
  app.add_option("scenario", scenario_path, "Scenario JSON file ('-' or omitted: defaults)");
  app.add_option("--out", out_dir, "Output directory")->required();
  app.add_option("--set", overrides, "Override a scenario field: path.to.field=value (repeatable)");
  app.add_option("--png", png_path, "Also render a picture of the heart to this PNG file");
  app.add_flag("--markers", markers, "Also write the tiled marker meshes (markers.h5/.xdmf)");
  CLI11_PARSE(app, argc, argv);
  try {
    nlohmann::json doc = nlohmann::json::object();
    if (!scenario_path.empty() && scenario_path != "-") {
      std::ifstream in(scenario_path);
      if (!in) throw InputError("cannot open scenario '" + scenario_path + "'");
      try {
        in >> doc;
      } catch (const nlohmann::json::exception& e) {
        throw InputError("scenario '" + scenario_path + "' is not valid JSON: " + e.what());
      }
    }
    doc["scene"] = "lumped";  // ignored by this command (see the header comment)
    for (const auto& o : overrides) config::apply_override(doc, o);
    const config::Scenario s = config::parse_scenario(doc);
    const LeftHeart heart = build_left_heart(s.geometry, s.fluid);
    const double target = s.geometry.marker_spacing_fraction * eulerian_spacing_mm(s.fluid);
    const MarkerPlan plan = plan_markers(heart, target);

    fs::create_directories(out_dir);
    for (const auto& b : heart.bodies) write_vtk(fs::path(out_dir) / (b.name + ".vtk"), b);
    write_xdmf_hdf5(fs::path(out_dir) / "heart", heart.body_pointers());
    if (markers) {
      std::vector<TriMesh> tiled;
      for (std::size_t b = 0; b < heart.bodies.size(); ++b) tiled.push_back(tile(heart.bodies[b], plan.level[b]));
      std::vector<const TriMesh*> ptrs;
      for (const auto& t : tiled) ptrs.push_back(&t);
      write_xdmf_hdf5(fs::path(out_dir) / "markers", ptrs);
    }
    nlohmann::json summary = heart_summary(heart, plan);
    summary["eulerian_spacing_mm"] = eulerian_spacing_mm(s.fluid);
    summary["geometry"] = config::to_json(s)["geometry"];
    std::ofstream(fs::path(out_dir) / "summary.json") << summary.dump(2) << "\n";
    if (!png_path.empty()) {
      using render::View;
      const std::vector<std::string> valves = {"valvular_plane", "mitral_anterior", "mitral_posterior",
                                               "aortic_cusp_1", "aortic_cusp_2", "aortic_cusp_3"};
      render::render_png(png_path, heart.body_pointers(),
                         {View{"anterior", Vec3(-1, 0.3, 0.3), -Vec3::UnitZ(), {}, true},
                          View{"posterior", Vec3(1, 0.45, 0.3), -Vec3::UnitZ(), {}, true},
                          View{"from above", Vec3(0.35, -0.35, 1), Vec3::UnitX(), {}, true},
                          View{"valves from the LV", Vec3(0.3, 0.5, -1), -Vec3::UnitX(), valves, true}},
                         700);
    }
    std::cout << "LV cavity " << summary["lv_cavity_volume_ml"].get<double>() << " ml, LA cavity "
              << summary["la_cavity_volume_ml"].get<double>() << " ml, " << summary["totals"]["triangles"]
              << " triangles (" << summary["totals"]["marker_triangles"] << " after tiling to "
              << target << " mm); written to " << out_dir << "\n";
  } catch (const InputError& e) {
    std::cerr << "systole-geometry: " << e.what() << "\n";
    return 2;
  } catch (const std::exception& e) {
    std::cerr << "systole-geometry: internal error: " << e.what() << "\n";
    return 3;
  }
  return 0;
}
