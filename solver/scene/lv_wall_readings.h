#pragma once
// Readings of a deformed LV wall against its stress-free mesh (issue #60, item 1): the global
// strains and twist of solver/diagnostics/kinematics, and the edge strains eps = (l - l0)/l
// (eq 17's measure) grouped by the edge's direction to the fibre of its triangles, so that a
// wall that locks in its fibre direction (the Fung law in compression) is told apart from one
// that shortens by shear or twist.
#include <map>
#include <string>

#include "solver/structure/shell.h"

namespace systole::scene {

// Edge directions: "fibre" when cos^2 phi >= 3/4 (within 30 deg of the fibre), "cross" when
// cos^2 phi <= 1/4 (within 30 deg of the cross-fibre direction), else "oblique"; cos^2 phi is
// the mean over the edge's triangles of (e . f)^2 in the stress-free mesh, as the springs'
// alpha_phi (shell.h).
//
// Adds to `metrics` (prefix + name):
//   twist_deg, gls_percent, gcs_percent   (kinematics.h; from the stress-free shape)
//   fibre_stretch_mean                    (area-weighted mean over the triangles of |F f0|)
//   edge_strain_<dir>_{p05,p50,p95,min,max}, edges_<dir>   for dir in fibre, cross, oblique.
// The LV mesh must carry the kLvApexRing / kLvBaseRing tags; throws std::invalid_argument
// otherwise (kinematics.h).
void add_lv_wall_readings(const structure::ShellModel& lv, const std::string& prefix,
                          std::map<std::string, double>& metrics);

}  // namespace systole::scene
