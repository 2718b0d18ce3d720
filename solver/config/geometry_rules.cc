#include "solver/config/geometry_rules.h"

#include <sstream>

namespace systole::config {

void check_geometry_rules(const Geometry& g, std::vector<std::string>& errors) {
  std::ostringstream m;
  if (g.mitral_diameter_mm >= g.lv_short_axis_mm) {
    m << "geometry.mitral_diameter_mm = " << g.mitral_diameter_mm
      << " must be smaller than geometry.lv_short_axis_mm = " << g.lv_short_axis_mm;
    errors.push_back(m.str());
    m.str("");
  }
  if (g.aortic_diameter_mm >= g.aortic_root_diameter_mm) {
    m << "geometry.aortic_diameter_mm = " << g.aortic_diameter_mm
      << " must be smaller than geometry.aortic_root_diameter_mm = " << g.aortic_root_diameter_mm;
    errors.push_back(m.str());
    m.str("");
  }
}

}  // namespace systole::config
