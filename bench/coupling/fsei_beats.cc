// Beat metrics of scenes fsi/fsei re-derived from a run's time_series.csv (the scene's own
// definitions, scene::fsei_beat_metrics): for runs recorded before a definition changed, and for
// reading one beat of a long run without its metrics.json.
//   fsei_beats DIR/time_series.csv PERIOD_MS [BLOOD_DENSITY_KG_PER_M3]
// The density (the run's fluid.density_kg_per_m3; by default the parameter's default) enters
// the mitral valve's effective orifice area. Prints one JSON object per whole beat on stdout.
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "solver/config/parameter_table.h"
#include "solver/core/errors.h"
#include "solver/scene/fsei_scene.h"

int main(int argc, char** argv) {
  try {
    if (argc != 3 && argc != 4)
      throw systole::InputError("usage: fsei_beats TIME_SERIES_CSV PERIOD_MS [BLOOD_DENSITY_KG_PER_M3]");
    std::ifstream in(argv[1]);
    if (!in) throw systole::InputError(std::string("cannot read '") + argv[1] + "'");
    const double period_ms = std::stod(argv[2]);
    if (!(period_ms > 0)) throw systole::InputError("PERIOD_MS must be > 0, got " + std::string(argv[2]));
    const double density_kg_per_m3 =
        argc == 4 ? std::stod(argv[3]) : systole::config::find_parameter("fluid.density_kg_per_m3")->default_number;
    if (!(density_kg_per_m3 > 0))
      throw systole::InputError("BLOOD_DENSITY_KG_PER_M3 must be > 0, got " + std::to_string(density_kg_per_m3));
    std::vector<systole::Series> series;
    std::string line, cell;
    std::getline(in, line);
    for (std::istringstream header(line); std::getline(header, cell, ',');) series.push_back({cell, "", {}});
    for (std::size_t row = 2; std::getline(in, line); ++row) {
      if (line.empty()) continue;
      std::istringstream cells(line);
      for (auto& s : series) {
        if (!std::getline(cells, cell, ','))
          throw systole::InputError("row " + std::to_string(row) + " has fewer cells than the header");
        s.values.push_back(std::stod(cell));
      }
    }
    for (const auto& beat : systole::scene::fsei_beat_metrics(series, period_ms, density_kg_per_m3, "fsi"))
      std::printf("%s\n", nlohmann::json(beat).dump(2).c_str());
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fsei_beats: %s\n", e.what());
    return 2;
  }
}
