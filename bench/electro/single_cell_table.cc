// Paces every cell model at 1 Hz and prints the AP biomarkers of the last beat (the table of
// docs/electro.md). Usage: electro_single_cell_table [beats] [dt_ms]
#include <cstdio>
#include <cstdlib>

#include "solver/electro/ionic/cell_model.h"
#include "solver/electro/single_cell.h"

int main(int argc, char** argv) {
  const int beats = argc > 1 ? std::atoi(argv[1]) : 100;
  const double dt = argc > 2 ? std::atof(argv[2]) : 0.01;
  std::printf("| model | beats | rest (mV) | peak (mV) | dV/dt max (V/s) | APD50 (ms) | APD90 (ms) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  for (const auto& name : systole::electro::ionic::cell_model_names()) {
    if (name == "ttp06") continue;  // alias of ttp06_epi
    const double amp = name.rfind("ttp06", 0) == 0 ? 52.0 : 35.0;
    const double dur = name.rfind("ttp06", 0) == 0 ? 1.0 : 2.0;
    const auto b = systole::electro::pace_single_cell(name, {1000.0, beats, dt, amp, dur});
    std::printf("| %s | %d | %.1f | %.1f | %.0f | %.0f | %.0f |\n", name.c_str(), beats, b.rest_mv, b.peak_mv,
                b.dvdt_max_v_per_s, b.apd50_ms, b.apd90_ms);
  }
}
