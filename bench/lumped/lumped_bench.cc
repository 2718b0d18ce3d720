// Wall time of the 0-D scene: 10 beats of the default scenario (goal < 10 ms).
#include <benchmark/benchmark.h>

#include "solver/config/scenario.h"
#include "solver/lumped/simulate.h"

namespace {

void BM_LumpedTenBeats(benchmark::State& state) {
  systole::config::Scenario s = systole::config::default_scenario();
  s.beats = 10;
  s.periodicity_tolerance = 0;  // exactly 10 beats
  for (auto _ : state) {
    systole::RunResult r = systole::lumped::simulate(s);
    benchmark::DoNotOptimize(r);
  }
  state.SetLabel("10 beats, default scenario, outputs as default");
}
BENCHMARK(BM_LumpedTenBeats)->Unit(benchmark::kMillisecond);

void BM_LumpedTenBeatsNoSeries(benchmark::State& state) {
  systole::config::Scenario s = systole::config::default_scenario();
  s.beats = 10;
  s.periodicity_tolerance = 0;
  s.outputs.time_series = false;
  s.outputs.metrics = false;
  for (auto _ : state) {
    systole::RunResult r = systole::lumped::simulate(s);
    benchmark::DoNotOptimize(r);
  }
}
BENCHMARK(BM_LumpedTenBeatsNoSeries)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
