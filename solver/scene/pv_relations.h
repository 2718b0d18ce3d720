#pragma once
// The LV's pressure-volume relations (issue #60, item 4): fits of the points that scene
// "mechanics" (structure.protocol = "pv_relations") measures at rest.
//   ESPVR (end-systolic, at a fixed active tension): P = E_es (V - V0), least squares.
//   EDPVR (end-diastolic, passive): P = A (exp(beta (V - V0)) - 1) with V0 the unloaded volume,
//   beta by a bracketed 1-D search and A by least squares for each beta.
#include <vector>

namespace systole::scene {

struct PvPoint {
  double pressure_mmhg;
  double volume_ml;
};

struct EspvrFit {
  double e_es_mmhg_per_ml;
  double v0_ml;  // the volume intercept at 0 mmHg
  double r2;     // coefficient of determination of P on V
};
// Throws std::invalid_argument for fewer than 2 points or points of one volume.
EspvrFit fit_espvr(const std::vector<PvPoint>& points);

struct EdpvrFit {
  double v0_ml;          // the first point's volume (its pressure must be 0)
  double a_mmhg;
  double beta_per_ml;    // the exponent: the chamber's passive stiffening per ml
  double rms_mmhg;       // r.m.s. residual of P
};
// Needs the unloaded point first (pressure 0) and at least 2 loaded points with volumes above
// it; throws std::invalid_argument otherwise. beta is searched on [1e-5, 5] per ml.
EdpvrFit fit_edpvr(const std::vector<PvPoint>& points);

}  // namespace systole::scene
