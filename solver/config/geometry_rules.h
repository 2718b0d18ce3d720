#pragma once
// Cross-field rules of the geometry variant (orifices vs plane, leaflets vs chamber, bodies
// that would intersect). Called by parse_scenario(); appends one message per violated rule,
// each naming the fields, their values and what is allowed.
#include <string>
#include <vector>

#include "solver/config/scenario.h"

namespace systole::config {
void check_geometry_rules(const Geometry& geometry, std::vector<std::string>& errors);
}
