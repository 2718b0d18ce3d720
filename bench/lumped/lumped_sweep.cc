// Calibration helper (solver/lumped/README.md "Calibration"): runs the 0-D scene for the
// default scenario with `path=value` overrides and prints the summary metrics on one line.
//   lumped_sweep [--beats-table] [--series] path=value ...
// --series prints the last beat's time series (columns as RunResult.series), e.g. with
// outputs.time_series_interval_ms=10.
// Several scenarios: separate their override groups with "--", one line each.
#include <cstdio>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/errors.h"
#include "solver/lumped/simulate.h"

namespace {
void run(const std::vector<std::string>& overrides, bool beats_table, bool series) {
  nlohmann::json doc = nlohmann::json::object();
  for (const auto& o : overrides) systole::config::apply_override(doc, o);
  const systole::config::Scenario s = systole::config::parse_scenario(doc);
  try {
    const systole::RunResult r = systole::lumped::simulate(s);
    if (series && !r.series.empty())
      for (size_t i = 0; i < r.series[0].values.size(); ++i) {
        for (const auto& c : r.series) std::printf("%10.4f ", c.values[i]);
        std::printf("\n");
      }
    if (beats_table)
      for (const auto& b : r.beats)
        std::printf("beat %2.0f EDV %8.3f ESV %7.3f EF %6.3f rel %.2e\n", b.at("beat"),
                    b.at("edv_ml"), b.at("esv_ml"), b.at("ejection_fraction_percent"),
                    b.at("edv_relative_change"));
    auto g = [&](const char* k) {
      auto it = r.metrics.find(k);
      return it == r.metrics.end() ? -1.0 : it->second;
    };
    for (const auto& o : overrides) std::printf("%s ", o.c_str());
    std::printf(
        "| EDV %.1f ESV %.1f EF %.1f CO %.2f LVpk %.1f@%.3f Ao %.1f/%.1f mean %.1f EDP %.1f "
        "AVO %.3f AVC %.3f MVC %.3f MVO %.3f E %.3f A %.3f E/A %.2f beats %.0f per %.0f\n",
        g("edv_ml"), g("esv_ml"), g("ejection_fraction_percent"), g("cardiac_output_l_min"),
        g("lv_peak_pressure_mmhg"), g("lv_peak_pressure_phase"), g("aortic_pressure_max_mmhg"),
        g("aortic_pressure_min_mmhg"), g("aortic_pressure_mean_mmhg"),
        g("lv_end_diastolic_pressure_mmhg"), g("aortic_valve_open_phase"),
        g("aortic_valve_close_phase"), g("mitral_valve_close_phase"), g("mitral_valve_open_phase"),
        g("mitral_e_peak_phase"), g("mitral_a_peak_phase"), g("mitral_e_to_a_ratio"),
        g("beats_simulated"), g("periodic"));
  } catch (const systole::InstabilityError& e) {
    std::printf("unstable: %s\n", e.what());
  }
}
}  // namespace

int main(int argc, char** argv) {
  bool beats_table = false, series = false;
  std::vector<std::string> group;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--beats-table") {
      beats_table = true;
    } else if (a == "--series") {
      series = true;
    } else if (a == "--") {
      run(group, beats_table, series);
      group.clear();
    } else {
      group.push_back(a);
    }
  }
  run(group, beats_table, series);
  return 0;
}
