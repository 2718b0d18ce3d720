// Study behind the "fhn_atrial" parameter set (ours, docs/electro.md "The LA"): the FitzHugh–Nagumo
// model with its fast (Vm) equation sped up by a factor k (c1 -> k c1, c2 -> k c2). The front
// speed of the bistable cubic scales as sqrt(k c1 D) (1 - 2a), so k sets the conduction velocity.
// Prints, per k applied to the given model (default fhn_atrial, k = 1), the CV along the fibres
// of a 40 x 4 mm sheet with the seed's monodomain conductivity at h = 2, 1, 0.5 mm (dt 0.05 ms).
// Usage: electro_fhn_atrial_study [model] [k ...]
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "solver/electro/ionic/cell_model.h"
#include "solver/electro/single_cell.h"
#include "solver/electro/tissue.h"

using namespace systole::electro;

namespace {

TissueOptions options(double dt, const std::string& model) {
  TissueOptions o;
  o.formulation = Formulation::kMonodomain;
  o.splitting = Splitting::kGodunov;
  o.dt_ms = dt;
  o.chi_per_cm = 1400.0;
  o.cm_uf_per_cm2 = 1.0;
  o.sigma_i = {7.0, 0.8};
  o.sigma_e = {25.0, 9.5};
  o.domain_cell_models = {model};
  o.activation_threshold_mv = -40.0;
  o.tension_k_kpa = 0.0;
  StimulusSpec st;
  st.name = "box";
  st.region.kind = StimulusRegion::Kind::kBox;
  st.region.box_min_mm = Vec3(-1, -1, -1);
  st.region.box_max_mm = Vec3(2.5, 100, 100);
  st.amplitude_ua_per_cm2 = 35.0;
  st.duration_ms = 2.0;
  st.start_ms = 0.0;
  st.period_ms = 0.0;
  o.stimuli = {st};
  return o;
}

double activation_near(const TissueSolver& s, double x) {
  double best = 1e300, t = NAN;
  for (std::size_t i = 0; i < s.mesh().node_count(); ++i) {
    const auto& p = s.mesh().position_mm[i];
    const double d = std::abs(p.x() - x) + std::abs(p.y() - 2.0);
    if (d < best) {
      best = d;
      t = s.activation().activation_ms()[i];
    }
  }
  return t;
}

}  // namespace

int main(int argc, char** argv) {
  const std::string model = argc > 1 ? argv[1] : "fhn_atrial";
  std::vector<double> ks;
  for (int i = 2; i < argc; ++i) ks.push_back(std::atof(argv[i]));
  if (ks.empty()) ks = {1};
  for (double k : ks) {
    auto m = ionic::make_cell_model(model, 1);
    const double c1 = m->parameter("c1") * k, c2 = m->parameter("c2") * k;
    std::printf("%s, k = %.1f (c1 = %.3f /ms, c2 = %.3f /ms)\n", model.c_str(), k, c1, c2);
    for (double h : {2.0, 1.0, 0.5}) {
      TissueSolver s(make_sheet(40.0, 4.0, h, 0.0), options(0.05, model));
      s.cell_model(0).set_parameter("c1", c1);
      s.cell_model(0).set_parameter("c2", c2);
      while (std::isnan(activation_near(s, 30.0)) && s.time_ms() < 400.0) s.step();
      const double t10 = activation_near(s, 10.0), t30 = activation_near(s, 30.0);
      std::printf("  h = %.2f mm: activation x=10: %.2f ms, x=30: %.2f ms, CV = %.3f m/s\n", h, t10, t30,
                  20.0 / (t30 - t10));
    }
  }
}
