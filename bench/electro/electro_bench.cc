// Electrophysiology costs (docs/electro.md, docs/benchmarks.md):
//  1. ionic updates per second of every cell model (10^4 nodes, 200 steps);
//  2. one diffusion step (monodomain / bidomain, Godunov / Strang) on a slab;
//  3. the Niederer et al. 2011 N-version slab (20 x 7 x 3 mm, TTP06 epi, monodomain,
//     1.5 mm corner stimulus) at the spacings given: activation time of the far corner.
//  4. threads: the reaction step of a TTP06 sheet (~5 000 nodes, 1 000 steps) on 1 and 2
//     OpenMP threads (TissueOptions::threads), wall seconds of the reaction stage.
// Usage: electro_bench [ionic|diffusion|niederer|threads] [niederer spacings_mm...]
#include <chrono>
#include <cmath>
#include <ctime>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "solver/electro/ionic/cell_model.h"
#include "solver/electro/tissue.h"

using namespace systole::electro;
using Clock = std::chrono::steady_clock;

static double seconds(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

static void ionic_rates() {
  const std::size_t n = 10000;
  const int steps = 200;
  std::printf("| model | CPU ns per node per step | node updates per CPU s |\n|---|---|---|\n");
  std::vector<std::string> names(ionic::cell_model_names().begin(), ionic::cell_model_names().end());
  names.push_back("ttp06_epi exact gates");
  for (const auto& label : names) {
    if (label == "ttp06") continue;
    const bool exact = label == "ttp06_epi exact gates";
    const std::string name = exact ? "ttp06_epi" : label;
    auto m = ionic::make_cell_model(name, n);
    if (exact) m->set_parameter("lookup_table", 0.0);
    std::vector<double> vm(n, m->resting_potential_mv() + 5.0), iion(n);
    const double dt = std::min(0.02, m->max_stable_dt_ms());
    // CPU time of this process (the machine is shared: wall time would count other jobs).
    const std::clock_t c0 = std::clock();
    for (int s = 0; s < steps; ++s) {
      m->compute({0, n}, dt, vm.data(), iion.data());
      for (std::size_t i = 0; i < n; ++i) vm[i] -= dt * iion[i];
    }
    const double t = static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC;
    std::printf("| %s | %.1f | %.3g |\n", label.c_str(), 1e9 * t / (n * steps), n * steps / t);
  }
}

static TissueOptions options(Formulation f, Splitting s, double dt, double sx) {
  TissueOptions o;
  o.formulation = f;
  o.splitting = s;
  o.dt_ms = dt;
  o.chi_per_cm = 1400.0;
  o.cm_uf_per_cm2 = 1.0;
  o.domain_cell_models = {"ttp06_epi"};
  o.activation_threshold_mv = 0.0;
  o.tension_k_kpa = 50.0;
  StimulusSpec st;
  st.name = "corner";
  st.region.kind = StimulusRegion::Kind::kBox;
  st.region.box_min_mm = Vec3::Constant(-1e-9);
  st.region.box_max_mm = Vec3::Constant(sx + 1e-9);
  st.amplitude_ua_per_cm2 = 50000.0 / 1400.0;  // Niederer: 50 000 uA/cm^3 / chi
  st.duration_ms = 2.0;
  st.start_ms = 0.0;
  st.period_ms = 0.0;
  o.stimuli = {st};
  // Niederer et al. 2011: sigma_i = 0.17 / 0.019 S/m, sigma_e = 0.62 / 0.24 S/m (x10 -> mS/cm).
  o.sigma_i = {1.7, 0.19};
  o.sigma_e = {6.2, 2.4};
  return o;
}

static void diffusion_cost() {
  std::printf("| formulation | splitting | nodes | unknowns | setup s | ms per step (diffusion) | ms per step (reaction) |\n");
  std::printf("|---|---|---|---|---|---|---|\n");
  const ElectroMesh mesh = make_slab(20.0, 7.0, 3.0, 0.25, 0.0);
  for (Formulation f : {Formulation::kMonodomain, Formulation::kBidomain})
    for (Splitting s : {Splitting::kGodunov, Splitting::kStrang}) {
      const auto t0 = Clock::now();
      TissueSolver t(mesh, options(f, s, 0.05, 1.5));
      const double setup = seconds(t0);
      const int steps = 40;
      for (int k = 0; k < steps; ++k) t.step();
      std::printf("| %s | %s | %zu | %zu | %.2f | %.2f | %.2f |\n", f == Formulation::kMonodomain ? "mono" : "bi",
                  s == Splitting::kGodunov ? "godunov" : "strang", mesh.node_count(), t.diffusion_unknowns(), setup,
                  1e3 * t.diffusion_seconds() / steps, 1e3 * t.reaction_seconds() / steps);
    }
}

static void niederer(const std::vector<double>& hs, double dt) {
  std::printf("| h (mm) | dt (ms) | nodes | corner (20,7,3) activation (ms) | wall s |\n|---|---|---|---|---|\n");
  for (double h : hs) {
    const auto t0 = Clock::now();
    TissueSolver t(make_slab(20.0, 7.0, 3.0, h, 0.0), options(Formulation::kMonodomain, Splitting::kGodunov, dt, 1.5));
    std::size_t corner = t.mesh().node_count() - 1;  // (20, 7, 3) is the last node
    std::size_t mid = 0;
    double best = 1e300;
    for (std::size_t i = 0; i < t.mesh().node_count(); ++i) {
      const double d = (t.mesh().position_mm[i] - Vec3(10, 3.5, 1.5)).norm();
      if (d < best) {
        best = d;
        mid = i;
      }
    }
    while (std::isnan(t.activation().activation_ms()[corner]) && t.time_ms() < 200) t.step();
    std::printf("| %.3f | %.3f | %zu | %.2f (centre %.2f) | %.1f |\n", h, dt, t.mesh().node_count(),
                t.activation().activation_ms()[corner], t.activation().activation_ms()[mid], seconds(t0));
    std::fflush(stdout);
  }
}

static void reaction_threads() {
  std::printf("| threads | nodes | steps | reaction wall (s) | diffusion wall (s) | process CPU (s) |\n|---|---|---|---|---|---|\n");
  for (int threads : {1, 2}) {
    TissueOptions o;
    o.formulation = Formulation::kMonodomain;
    o.splitting = Splitting::kGodunov;
    o.dt_ms = 0.05;
    o.chi_per_cm = 1400;
    o.cm_uf_per_cm2 = 1;
    o.sigma_i = {7.0, 0.8};
    o.sigma_e = {25.0, 9.5};
    o.domain_cell_models = {"ttp06_epi"};
    o.activation_threshold_mv = -40;
    o.tension_k_kpa = 0;
    StimulusSpec st;
    st.name = "box";
    st.region.kind = StimulusRegion::Kind::kBox;
    st.region.box_min_mm = Vec3(-1, -1, -1);
    st.region.box_max_mm = Vec3(1.5, 100, 100);
    st.amplitude_ua_per_cm2 = 50;
    st.duration_ms = 2;
    st.start_ms = 0;
    st.period_ms = 0;
    o.stimuli = {st};
    o.threads = threads;
    TissueSolver t(make_sheet(70.0, 35.0, 0.5, 0.0), o);
    const std::clock_t c0 = std::clock();
    const int steps = 1000;
    for (int s = 0; s < steps; ++s) t.step();
    std::printf("| %d | %zu | %d | %.2f | %.2f | %.2f |\n", threads, t.mesh().node_count(), steps, t.reaction_seconds(),
                t.diffusion_seconds(), static_cast<double>(std::clock() - c0) / CLOCKS_PER_SEC);
    std::fflush(stdout);
  }
}

int main(int argc, char** argv) {
  const std::string what = argc > 1 ? argv[1] : "all";
  if (what == "threads" || what == "all") reaction_threads();
  if (what == "ionic" || what == "all") ionic_rates();
  if (what == "diffusion" || what == "all") diffusion_cost();
  if (what == "niederer" || what == "all") {
    std::vector<double> hs;
    double dt = 0.05;
    for (int k = 2; k < argc; ++k) {
      const std::string a = argv[k];
      if (a.rfind("dt=", 0) == 0) dt = std::atof(a.c_str() + 3);
      else hs.push_back(std::atof(a.c_str()));
    }
    if (hs.empty()) hs = {0.5, 0.25};
    niederer(hs, dt);
  }
}
