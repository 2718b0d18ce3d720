// The aorta alone, without blood, inflated quasi-statically from its ground pressure
// (scene::AortaInflation): the lumen's volume against the inner pressure and its compliance
// dV/dp, for a share of the ground pressure carried by the wall's pre-stress (the rest by an
// outer load). The dry counterpart of the afterload of scenes fsi and fsei (docs/fsei.md).
//   aorta_compliance [fraction=1] [ground_mmhg=60] [from_mmhg=40] [to_mmhg=140] [step_mmhg=10]
//                    [damping_per_ms=0.5] [path=value ...]
// fraction 1 is fsei.aorta.pretension = prestress, 0 the outer load. The pressures are held in
// the order ground, ground + step, ..., to, then ground - step, ..., from (each from the settled
// state of the one before; the descent restarts from the ground pressure). Prints per level:
// pressure, volume change from the built shape, the compliance against the previous level,
// the largest and smallest edge strains, the largest displacement, settled or not, the clock.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/rigs/aorta_inflation.h"

using namespace systole;

int main(int argc, char** argv) {
  try {
    double fraction = 1, ground = 60, from = 40, to = 140, step = 10, damping = 0.5;
    nlohmann::json doc = nlohmann::json::object();
    for (int a = 1; a < argc; ++a) {
      const std::string arg = argv[a];
      const auto eq = arg.find('=');
      if (eq == std::string::npos)
        throw InputError("usage: aorta_compliance [fraction=1] [ground_mmhg=60] [from_mmhg=40] [to_mmhg=140] "
                         "[step_mmhg=10] [damping_per_ms=0.5] [path=value ...]; got '" + arg + "'");
      const std::string key = arg.substr(0, eq);
      const auto value = [&] { return std::stod(arg.substr(eq + 1)); };
      if (key == "fraction") fraction = value();
      else if (key == "ground_mmhg") ground = value();
      else if (key == "from_mmhg") from = value();
      else if (key == "to_mmhg") to = value();
      else if (key == "step_mmhg") step = value();
      else if (key == "damping_per_ms") damping = value();
      else config::apply_override(doc, arg);
    }
    if (!(step > 0)) throw InputError("aorta_compliance: step_mmhg must be > 0");
    doc["scene"] = "fsi";
    const config::Scenario s = config::parse_scenario(doc);
    std::printf("# aorta, ground pressure %.1f mmHg, share carried by the pre-stress %.2f, c %.1f Pa, damping %.2f /ms\n",
                ground, fraction, s.tissue.aorta.fung_c_pa, damping);
    std::printf("# p_mmhg dV_ml C_ml_per_mmhg max_strain min_strain max_disp_mm settled t_ms\n");
    for (int branch = 0; branch < 2; ++branch) {
      scene::AortaInflation aorta(s, ground, fraction, damping);
      std::vector<double> levels;
      if (branch == 0)
        for (double p = ground; p <= to + 1e-9; p += step) levels.push_back(p);
      else
        for (double p = ground - step; p >= from - 1e-9; p -= step) levels.push_back(p);
      double p_prev = ground, v_prev = 0;
      for (double p : levels) {
        const scene::AortaInflationPoint r = aorta.hold(p);
        const double c = p != p_prev ? (r.volume_change_ml - v_prev) / (p - p_prev) : NAN;
        std::printf("%6.1f %8.3f %7.3f %7.4f %7.4f %7.3f %d %7.1f\n", r.pressure_mmhg, r.volume_change_ml, c, r.max_strain,
                    r.min_strain, r.max_displacement_mm, r.settled ? 1 : 0, r.time_ms);
        std::fflush(stdout);
        p_prev = p;
        v_prev = r.volume_change_ml;
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "aorta_compliance: %s\n", e.what());
    return 1;
  }
  return 0;
}
