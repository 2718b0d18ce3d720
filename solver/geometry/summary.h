#pragma once
// Summary of a built heart as JSON (the systole-geometry command's summary.json): volumes,
// areas, counts, quality per body, layout numbers, tiling level for a marker spacing.
#include <nlohmann/json.hpp>

#include "solver/config/scenario.h"
#include "solver/geometry/left_heart.h"

namespace systole::geometry {

// Eulerian spacing of the fluid grid (mm): min over axes of box / (n - 1) (ours, until
// solver/grid defines its own accessor).
double eulerian_spacing_mm(const config::Fluid& fluid);

// Marker tiling of every body to spacing <= target_mm: per-body level m (>= 1).
struct MarkerPlan {
  double target_mm = 0;
  std::vector<int> level;  // per body, same order as LeftHeart::bodies
};
MarkerPlan plan_markers(const LeftHeart& heart, double target_mm);

nlohmann::json heart_summary(const LeftHeart& heart, const MarkerPlan& plan);

}  // namespace systole::geometry
