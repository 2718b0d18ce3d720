// What one sample of the chambers' kinetic energy costs (scenes fsi/fsei, series
// heart_kinetic_energy_mj): the two ray-parity scans of solver/scene/fsei/chamber_cells.h (the LV's and
// the LA's cells at the built shapes) plus the sum of |u|² over the cells found, on one rank over
// the whole box, at a resolution preset. The scene does this once per time-series sample
// (outputs.time_series_interval_ms, 1 ms by default), each rank over its own slab.
//   chamber_cells_cost [coarse|basic|fine|very_fine] [repeats=20]
// Prints the grid, the triangles scanned, the cells found and the mean wall time per sample (ms).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/fsei/chamber_cells.h"
#include "solver/scene/fsei_scene.h"

using namespace systole;

int main(int argc, char** argv) {
  try {
    const std::string preset = argc > 1 ? argv[1] : "coarse";
    const int repeats = argc > 2 ? std::stoi(argv[2]) : 20;
    if (repeats < 1) throw InputError("repeats must be at least 1, got " + std::to_string(repeats));
    nlohmann::json doc = {{"scene", "fsi"}};
    config::apply_override(doc, "fsei.resolution=" + preset);
    const config::Scenario s = config::parse_scenario(doc);
    const config::GridPoints g = config::fsei_grid_points(s);
    // the cells' centres as the scene places them: spacing box / points per axis (a MAC grid of
    // n cells per axis over the box, as grid::Grid)
    const double hx = s.fluid.box_x_mm / g.nx, hy = s.fluid.box_y_mm / g.ny, hz = s.fluid.box_z_mm / g.nz;
    const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
    const geometry::TriMesh& lv = heart.body(geometry::kLvBody);
    const geometry::TriMesh& la = heart.body(geometry::kLaBody);
    const int lv_side = heart.lv_axis_direction.z() > 0 ? 1 : -1;
    const std::size_t cells = static_cast<std::size_t>(g.nx) * g.ny * g.nz;
    std::vector<double> u2(cells, 1.0);  // stands for u² + v² + w² per cell
    double sum = 0;
    std::size_t inside = 0;
    const auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < repeats; ++r) {
      const std::vector<char> in_heart = scene::heart_chambers_cells(lv.position_mm, lv.tri, la.position_mm, la.tri,
                                                                    heart.plane.z_mm, lv_side, g.nx, g.ny, 0, g.nz, hx,
                                                                    hy, hz);
      inside = 0;
      for (std::size_t c = 0; c < cells; ++c)
        if (in_heart[c]) sum += u2[c], ++inside;
    }
    const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count() / repeats;
    std::printf("preset %s: grid %dx%dx%d (%zu cells), triangles LV %zu + LA %zu, cells inside %zu (%.1f ml)\n",
                preset.c_str(), g.nx, g.ny, g.nz, cells, lv.tri.size(), la.tri.size(), inside,
                inside * hx * hy * hz * 1e-3);
    std::printf("%.3f ms per sample (mean of %d; checksum %.0f)\n", ms, repeats, sum);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "chamber_cells_cost: %s\n", e.what());
    return 1;
  }
}
