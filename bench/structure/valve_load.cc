// The closed valves alone (no blood) under a uniform pressure difference, ramped then held, with
// damping: does the valve carry the load, how far does it sag and how much do its edges strain?
// The dry counterpart of the fsei runs' first milliseconds (docs/fsei.md).
//   valve_load aortic|mitral [pressure_mmhg=60] [ramp_ms=10] [hold_ms=40] [damping_per_ms=0.5]
//              [cusp_limit_mm=0] [path=value ...]
// aortic: the three cusps, loaded from the aorta (-z side), optionally with a limiter on their
// displacement towards the LV (cusp_limit_mm > 0, a trial: the seed has none); mitral: the two
// leaflets loaded from the LV (+z side), with the scenario's limiter. Prints per ms: pressure,
// the largest displacement from the built shape, the largest and smallest edge strain, and the
// active contact pairs. VALVE_LOAD_DUMP=file writes the built and final node positions.
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <iterator>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/core/units.h"
#include "solver/geometry/left_heart.h"
#include "solver/scene/chamber_walls.h"
#include "solver/structure/contact.h"
#include "solver/structure/shell.h"

using namespace systole;

int main(int argc, char** argv) {
  try {
    if (argc < 2 || (std::string(argv[1]) != "aortic" && std::string(argv[1]) != "mitral"))
      throw InputError("usage: valve_load aortic|mitral [pressure_mmhg=60] [ramp_ms=10] [hold_ms=40] [damping_per_ms=0.5] [path=value ...]");
    const bool aortic = std::string(argv[1]) == "aortic";
    double p_mmhg = 60, ramp_ms = 10, hold_ms = 40, damping = 0.5, cusp_limit_mm = 0;
    nlohmann::json doc = nlohmann::json::object();
    for (int a = 2; a < argc; ++a) {
      const std::string arg = argv[a];
      const auto eq = arg.find('=');
      const std::string key = arg.substr(0, eq);
      if (key == "pressure_mmhg") p_mmhg = std::stod(arg.substr(eq + 1));
      else if (key == "ramp_ms") ramp_ms = std::stod(arg.substr(eq + 1));
      else if (key == "hold_ms") hold_ms = std::stod(arg.substr(eq + 1));
      else if (key == "damping_per_ms") damping = std::stod(arg.substr(eq + 1));
      else if (key == "cusp_limit_mm") cusp_limit_mm = std::stod(arg.substr(eq + 1));
      else config::apply_override(doc, arg);
    }
    const config::Scenario s = config::parse_scenario(doc);
    const geometry::LeftHeart heart = geometry::build_left_heart(s.geometry, s.fluid);
    const structure::ShellMaterials materials = scene::chamber_wall_materials(s);
    structure::ShellOptions o = scene::structure_options(s, heart.plane.z_mm);
    o.damping_per_ms = damping;
    std::vector<std::string_view> names;
    if (aortic) names.assign(std::begin(geometry::kAorticCuspBodies), std::end(geometry::kAorticCuspBodies));
    else names = {geometry::kMitralAnteriorBody, geometry::kMitralPosteriorBody};
    std::vector<structure::ShellModel> models;
    for (auto n : names) {
      models.emplace_back(heart.body(n), materials, o);
      if (aortic && cusp_limit_mm > 0) models.back().set_displacement_limit(geometry::Vec3::UnitZ(), cusp_limit_mm);
      if (!aortic && s.structure.mitral_limiter) models.back().set_displacement_limit(-geometry::Vec3::UnitZ(), s.structure.mitral_limit_mm);
    }
    structure::ContactOptions c;
    c.distance_mm = s.structure.contact_distance_mm;
    c.stiffness_kpa_per_mm = s.structure.contact_stiffness_kpa_per_mm;
    c.skin_mm = 0.5 * c.distance_mm;
    structure::BodyGroup group(std::move(models), c);
    // Leaflet normals face -z (the aorta / atrium side): set_cavity_pressure(p) pushes along -n,
    // i.e. +z (from the aorta into the LV); the LV's pressure on the mitral pushes -z.
    const double sign = aortic ? 1.0 : -1.0;
    const double p_kpa = p_mmhg * units::kPaPerMmHg * 1e-3;
    std::printf("# %s valve, %.1f mmHg ramped over %.1f ms, held %.1f ms, damping %.2f /ms, gap %.2f mm\n",
                argv[1], p_mmhg, ramp_ms, hold_ms, damping, s.geometry.valve_gap_mm);
    std::printf("# t_ms p_mmhg max_disp_mm max_strain min_strain contact_pairs\n");
    const double end = ramp_ms + hold_ms;
    for (double t = 0.5; t <= end + 1e-9; t += 0.5) {
      const double f = ramp_ms > 0 ? std::min(1.0, t / ramp_ms) : 1.0;
      for (std::size_t k = 0; k < group.body_count(); ++k) group.body(k).set_cavity_pressure(sign * f * p_kpa);
      group.advance(0.5);
      double disp = 0, emax = -1, emin = 1;
      for (std::size_t k = 0; k < group.body_count(); ++k) {
        const auto& x = group.body(k).positions_mm();
        const auto& x0 = heart.body(names[k]).position_mm;
        for (std::size_t i = 0; i < x.size(); ++i) disp = std::max(disp, (x[i] - x0[i]).norm());
        for (double e : group.body(k).edge_strains()) emax = std::max(emax, e), emin = std::min(emin, e);
      }
      if (std::abs(t - std::round(t)) < 1e-9)
        std::printf("%5.1f %7.2f %8.3f %8.4f %8.4f %d\n", t, f * p_mmhg, disp, emax, emin,
                    group.contact_stats().active);
    }
    if (const char* dump = std::getenv("VALVE_LOAD_DUMP")) {
      // the built and the final node positions, one line per node: body x0 y0 z0 x y z
      std::FILE* f = std::fopen(dump, "w");
      for (std::size_t k = 0; k < group.body_count(); ++k) {
        const auto& x = group.body(k).positions_mm();
        const auto& x0 = heart.body(names[k]).position_mm;
        for (std::size_t i = 0; i < x.size(); ++i)
          std::fprintf(f, "%zu %g %g %g %g %g %g\n", k, x0[i].x(), x0[i].y(), x0[i].z(), x[i].x(), x[i].y(), x[i].z());
      }
      std::fclose(f);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "valve_load: %s\n", e.what());
    return 1;
  }
  return 0;
}
