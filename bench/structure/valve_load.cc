// The closed valves alone (no blood) under a uniform pressure difference, ramped then held, with
// damping (scene::ClosedValveLoad): does the valve carry the load, how far does it sag and how
// much do its edges strain? The dry counterpart of the fsei runs' first milliseconds (docs/fsei.md).
//   valve_load aortic|mitral [pressure_mmhg=60] [ramp_ms=10] [hold_ms=40] [damping_per_ms=0.5]
//              [open_mmhg=0 open_ms=0] [path=value ...]
// aortic: the three cusps, loaded from the aorta; mitral: the two leaflets loaded from the LV
// (a negative pressure_mmhg opens the valve: loaded from the aorta's / the LA's side instead),
// with the scenario's limiter. open_ms > 0 first opens the valve: open_mmhg (< 0) ramped over
// ramp_ms and held for open_ms - ramp_ms, then the load ramps linearly from open_mmhg to
// pressure_mmhg over ramp_ms and is held (a dry open-close cycle: does the valve close again as
// it was built?). Prints per ms: pressure, the largest displacement from the built
// shape, the largest and smallest edge strain, the active contact pairs, the stable substep, the fastest node's speed and,
// for the mitral valve, the gap between the free edges' middles (its opening).
// VALVE_LOAD_DUMP=file writes, at the end or when the valve fails, one line per node
// (body x0 y0 z0 x y z) then one per triangle (-1-body a b c 0 0 0).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/scene/rigs/valve_load.h"

using namespace systole;

namespace {

void dump_state(const scene::ClosedValveLoad& load) {
  const char* path = std::getenv("VALVE_LOAD_DUMP");
  if (!path) return;
  std::FILE* f = std::fopen(path, "w");
  if (!f) return;
  const auto& names = load.body_names();
  for (std::size_t k = 0; k < names.size(); ++k) {
    const auto& x = load.group().body(k).positions_mm();
    const auto& x0 = load.heart().body(names[k]).position_mm;
    for (std::size_t i = 0; i < x.size(); ++i)
      std::fprintf(f, "%zu %g %g %g %g %g %g\n", k, x0[i].x(), x0[i].y(), x0[i].z(), x[i].x(), x[i].y(), x[i].z());
  }
  for (std::size_t k = 0; k < names.size(); ++k)
    for (const auto& t : load.heart().body(names[k]).tri)
      std::fprintf(f, "%d %d %d %d 0 0 0\n", -1 - static_cast<int>(k), t[0], t[1], t[2]);
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  try {
    if (argc < 2 || (std::string(argv[1]) != "aortic" && std::string(argv[1]) != "mitral"))
      throw InputError("usage: valve_load aortic|mitral [pressure_mmhg=60] [ramp_ms=10] [hold_ms=40] "
                       "[damping_per_ms=0.5] [path=value ...]");
    const bool aortic = std::string(argv[1]) == "aortic";
    double p_mmhg = 60, ramp_ms = 10, hold_ms = 40, damping = 0.5, open_mmhg = 0, open_ms = 0;
    nlohmann::json doc = nlohmann::json::object();
    for (int a = 2; a < argc; ++a) {
      const std::string arg = argv[a];
      const auto eq = arg.find('=');
      const std::string key = arg.substr(0, eq);
      if (key == "pressure_mmhg") p_mmhg = std::stod(arg.substr(eq + 1));
      else if (key == "ramp_ms") ramp_ms = std::stod(arg.substr(eq + 1));
      else if (key == "hold_ms") hold_ms = std::stod(arg.substr(eq + 1));
      else if (key == "damping_per_ms") damping = std::stod(arg.substr(eq + 1));
      else if (key == "open_mmhg") open_mmhg = std::stod(arg.substr(eq + 1));
      else if (key == "open_ms") open_ms = std::stod(arg.substr(eq + 1));
      else config::apply_override(doc, arg);
    }
    const config::Scenario s = config::parse_scenario(doc);
    scene::ClosedValveLoad load(s, aortic ? scene::Valve::kAortic : scene::Valve::kMitral, damping);
    if (open_ms < 0 || (open_ms > 0 && (open_mmhg >= 0 || open_ms < ramp_ms)))
      throw InputError("open_ms = " + std::to_string(open_ms) + ", open_mmhg = " + std::to_string(open_mmhg) +
                       ": an opening phase needs open_mmhg < 0 and open_ms >= ramp_ms (or open_ms = 0: none)");
    if (open_ms > 0)
      std::printf("# opened first: %.1f mmHg ramped over %.1f ms, held to %.1f ms\n", open_mmhg, ramp_ms, open_ms);
    std::printf("# %s valve, %.1f mmHg ramped over %.1f ms, held %.1f ms, damping %.2f /ms, gap %.2f mm\n",
                argv[1], p_mmhg, ramp_ms, hold_ms, damping, s.geometry.valve_gap_mm);
    if (!aortic && s.geometry.mitral_rest_opening_mm > 0) {
      double hi = 0, lo = 0;  // the built valve's edge strains from the rest shape
      for (std::size_t k = 0; k < load.group().body_count(); ++k)
        for (double e : load.group().body(k).edge_strains()) hi = std::max(hi, e), lo = std::min(lo, e);
      std::printf("# rest opening %.2f mm: the built valve starts pre-strained, edge strains %.4f .. %.4f\n",
                  s.geometry.mitral_rest_opening_mm, lo, hi);
    }
    std::printf("# t_ms p_mmhg max_disp_mm max_strain min_strain contact_pairs stable_step_ms max_speed_m_s%s\n",
                aortic ? "" : " free_edge_gap_mm");
    const double end = open_ms + ramp_ms + hold_ms;
    // the load at time t (ms): the opening phase (if any), then the ramp to p_mmhg and the hold
    const auto load_at = [&](double t) {
      const auto ramp = [&](double tau) { return ramp_ms > 0 ? std::min(1.0, tau / ramp_ms) : 1.0; };
      if (t <= open_ms) return ramp(t) * open_mmhg;
      const double f = ramp(t - open_ms);
      return (1 - f) * open_mmhg + f * p_mmhg;
    };
    try {
      for (double t = 0.5; t <= end + 1e-9; t += 0.5) {
        const scene::ValveLoadSample r = load.advance(0.5, load_at(t));
        if (std::abs(t - std::round(t)) < 1e-9) {
          std::printf("%5.1f %7.2f %8.3f %8.4f %8.4f %d %.3g %.3g", r.t_ms, r.pressure_mmhg, r.max_displacement_mm,
                      r.max_strain, r.min_strain, r.contact_pairs, r.stable_step_ms, r.max_speed_m_s);
          if (!aortic) std::printf(" %.2f", load.mitral_free_edge_gap_mm());
          std::printf("\n");
        }
      }
    } catch (const std::exception&) {
      dump_state(load);
      throw;
    }
    dump_state(load);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "valve_load: %s\n", e.what());
    return 1;
  }
  return 0;
}
