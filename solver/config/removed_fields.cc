#include "solver/config/removed_fields.h"

#include <sstream>

namespace systole::config {

const std::vector<RemovedField>& removed_fields() {
  static constexpr std::string_view kForcingGroup = "the immersed boundary's forcing is one group, fsei.forcing";
  static constexpr std::string_view kAortaGroup = "the aorta's ground pressure and how it is held are one group, fsei.aorta";
  static const std::vector<RemovedField> table{
      // Removed: refuted or unused (ARCHITECTURE.md rule 15; proto numbers reserved).
      {"fsei.forcing_row_sum_scaling", "",
       "refuted: the forcing passes' correction scaled by its row sums made the small-step runaway come earlier "
       "(70 bpm at CFL 0.2: 0.186 s against 0.229 s without; docs/notes/fsei-notebook.md); "
       "fsei.forcing.carry_over_reference_cfl completes that run",
       "false"},
      {"fsei.forcing_carry_over_factor", "", "unused: every run carried the whole force over (1)", "1"},
      {"fsei.stencil_tolerance_cells", "", "unused: every run rebuilt the stencils after any move (0)", "0"},
      {"fsei.marker_tiling", "",
       "only mean_edge was used, and it is now the only tiling (the mean tile edge <= 0.7 h, the longest <= h)",
       "mean_edge"},
      {"fsei.forcing_carry_over_increment_share", "",
       "unused: fsei.forcing.carry_over_reference_cfl sets the carried force's share of each step's corrections "
       "per step",
       "1"},
      // Moved into groups.
      {"fsei.forcing_kernel", "fsei.forcing.kernel", kForcingGroup},
      {"fsei.forcing_iterations", "fsei.forcing.iterations", kForcingGroup},
      {"fsei.forcing_carry_over", "fsei.forcing.carry_over", kForcingGroup},
      {"fsei.forcing_carry_over_exclusion_cells", "fsei.forcing.carry_over_exclusion_cells", kForcingGroup},
      {"fsei.forcing_carry_over_exclusion_plane", "fsei.forcing.carry_over_exclusion_plane", kForcingGroup},
      {"fsei.forcing_carry_over_exclusion_plane_cells", "fsei.forcing.carry_over_exclusion_plane_cells", kForcingGroup},
      {"fsei.forcing_carry_over_exclusion_plane_wall_cells", "fsei.forcing.carry_over_exclusion_plane_wall_cells",
       kForcingGroup},
      {"fsei.forcing_carry_over_reference_cfl", "fsei.forcing.carry_over_reference_cfl", kForcingGroup},
      {"fsei.aortic_pressure_mmhg", "fsei.aorta.ground_pressure_mmhg", kAortaGroup},
      {"fsei.aortic_pressure_ramp_ms", "fsei.aorta.pressure_ramp_ms", kAortaGroup},
      {"fsei.aortic_pretension", "fsei.aorta.pretension", kAortaGroup},
      {"fsei.aortic_prestress_fraction", "fsei.aorta.prestress_fraction", kAortaGroup},
      {"fsei.aortic_outlet_held", "fsei.aorta.outlet_held", kAortaGroup},
  };
  return table;
}

const RemovedField* find_removed_field(std::string_view path) {
  for (const RemovedField& f : removed_fields())
    if (f.path == path) return &f;
  return nullptr;
}

std::string removed_field_message(const RemovedField& f) {
  if (f.moved_to.empty())
    return std::string(f.path) + " was removed: " + std::string(f.why) + "; remove it from the scenario";
  return std::string(f.path) + " moved to " + std::string(f.moved_to) + " (" + std::string(f.why) +
         "); rename it in the scenario";
}

std::string removed_fields_markdown() {
  std::ostringstream out;
  out << "## Removed and moved fields\n\n"
      << "A scenario that names one of these is refused with the reason "
         "(solver/config/removed_fields.cc); a checkpoint written before the change still resumes.\n\n"
      << "| field | what happened | why |\n|---|---|---|\n";
  for (const RemovedField& f : removed_fields())
    out << "| `" << f.path << "` | "
        << (f.moved_to.empty() ? std::string("removed") : "moved to `" + std::string(f.moved_to) + "`") << " | "
        << f.why << " |\n";
  return out.str();
}

}  // namespace systole::config
