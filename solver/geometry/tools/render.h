#pragma once
// A tiny software rasteriser for pictures of the geometry (docs/img): orthographic views,
// z-buffer, Lambert shading, region tags painted on the nodes, fibres drawn as short strokes.
// Output: PNG through libpng (Debian libpng-dev).
#include <filesystem>
#include <string>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry::render {

struct View {
  std::string title;
  Vec3 forward;                       // viewing direction
  Vec3 up = -Vec3::UnitZ();           // screen up (the base of the heart is up)
  std::vector<std::string> bodies;    // empty: all
  bool fibres = true;
};

// Renders the views side by side (each panel_px square) and writes a PNG.
void render_png(const std::filesystem::path& path, const std::vector<const TriMesh*>& bodies,
                const std::vector<View>& views, int panel_px);

}  // namespace systole::geometry::render
