// Tissue verification: conduction velocity along / across fibres on a sheet and in a slab
// under refinement (observed orders), CV proportional to sqrt(sigma), Godunov vs Strang in
// time, bidomain = monodomain for proportional tensors, stimuli and bad input, active tension.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "solver/core/errors.h"
#include "solver/electro/tissue.h"

namespace systole::electro {
namespace {

// The seed's tissue constants (MODEL.md §6).
TissueOptions seed_options(Formulation f, Splitting s, double dt_ms, const std::string& model) {
  TissueOptions o;
  o.formulation = f;
  o.splitting = s;
  o.dt_ms = dt_ms;
  o.chi_per_cm = 1400.0;
  o.cm_uf_per_cm2 = 1.0;
  o.sigma_i = {7.0, 0.8};
  o.sigma_e = {25.0, 9.5};
  o.domain_cell_models = {model};
  o.activation_threshold_mv = -40.0;
  o.tension_k_kpa = 50.0;
  StimulusSpec st;
  st.name = "box";
  st.region.kind = StimulusRegion::Kind::kBox;
  st.region.box_min_mm = Vec3(-1, -1, -1);
  st.region.box_max_mm = Vec3(1.5, 100, 100);
  st.amplitude_ua_per_cm2 = 100.0;
  st.duration_ms = 2.0;
  st.start_ms = 0.0;
  st.period_ms = 0.0;
  o.stimuli = {st};
  return o;
}

// Activation time at the node nearest to p.
double activation_at(const TissueSolver& s, const Vec3& p) {
  std::size_t best = 0;
  double d = 1e300;
  for (std::size_t i = 0; i < s.mesh().node_count(); ++i) {
    const double di = (s.mesh().position_mm[i] - p).norm();
    if (di < d) {
      d = di;
      best = i;
    }
  }
  return s.activation().activation_ms()[best];
}

// CV (m/s = mm/ms) between x = 0.25 L and x = 0.75 L along a strip of length L whose fibres
// make the given angle with x; run until x = 0.75 L is active.
double strip_cv(const ElectroMesh& mesh, TissueOptions o) {
  TissueSolver s(mesh, std::move(o));
  const Vec3 far = mesh.position_mm.back();
  const Vec3 a(0.25 * far.x(), far.y() / 2, far.z() / 2), b(0.75 * far.x(), far.y() / 2, far.z() / 2);
  while (std::isnan(activation_at(s, b)) && s.time_ms() < 200.0) s.step();
  return 0.5 * far.x() / (activation_at(s, b) - activation_at(s, a));
}

double order(double e1, double e2, double ratio) { return std::log(e1 / e2) / std::log(ratio); }

// The reaction step on 2 OpenMP threads (TissueOptions::threads) is the serial one exactly: the
// cell models are per node, so disjoint node ranges give bit-identical potentials (TTP06 with its
// lookup table, built before the threads start).
TEST(Tissue, ThreadedReactionEqualsTheSerialOne) {
  auto run = [](int threads) {
    auto o = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.05, "ttp06_epi");
    o.threads = threads;
    TissueSolver s(make_sheet(4.0, 1.0, 0.1, 0.0), o);
    for (int k = 0; k < 200; ++k) s.step();
    return s.vm_mv();
  };
  const auto serial = run(1), threaded = run(2);
  ASSERT_EQ(serial.size(), threaded.size());
  double worst = 0, vmax = -1e9;
  for (std::size_t i = 0; i < serial.size(); ++i) {
    worst = std::max(worst, std::abs(serial[i] - threaded[i]));
    vmax = std::max(vmax, serial[i]);
  }
  std::printf("threads 2 vs 1: max |dVm| = %.3g mV (%zu nodes, max Vm %.1f mV)\n", worst, serial.size(), vmax);
  EXPECT_GT(vmax, 0.0);  // the front has passed: the comparison covers upstroke and plateau
  EXPECT_EQ(worst, 0.0);
  auto bad = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.05, "ttp06_epi");
  bad.threads = 0;
  EXPECT_THROW(TissueSolver(make_sheet(1.0, 1.0, 0.5, 0.0), bad), InputError);
}

// fhn_atrial (ours) with the seed's conductivities conducts along the fibres at the human atrial
// CV: Heida et al. 2021 (J Clin Med 10:2614, intra-operative epicardial mapping) report a
// biatrial median CV of 92 +- 6 cm/s in patients without AF; asserted within mean +- 2 SD
// (0.80-1.04 m/s) on the 2 mm mesh of the left heart and on a 0.5 mm mesh. The Sundnes set
// ("fhn") conducts at ~0.13 m/s, far below (the reason for fhn_atrial, docs/electro.md).
TEST(Tissue, FhnAtrialConductsAtTheHumanAtrialVelocity) {
  for (double h : {2.0, 0.5}) {
    auto o = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.05, "fhn_atrial");
    o.stimuli[0].amplitude_ua_per_cm2 = 35.0;
    o.stimuli[0].region.box_max_mm = Vec3(2.5, 100, 100);
    const double cv = strip_cv(make_sheet(40.0, 4.0, h, 0.0), o);
    std::printf("fhn_atrial, h = %.1f mm: CV along the fibres %.3f m/s\n", h, cv);
    EXPECT_GT(cv, 0.80);
    EXPECT_LT(cv, 1.04);
  }
  auto o = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.05, "fhn");
  o.stimuli[0].amplitude_ua_per_cm2 = 35.0;
  o.stimuli[0].region.box_max_mm = Vec3(2.5, 100, 100);
  const double cv_sundnes = strip_cv(make_sheet(16.0, 2.0, 1.0, 0.0), o);
  std::printf("fhn (Sundnes set), h = 1 mm: CV %.3f m/s\n", cv_sundnes);
  EXPECT_LT(cv_sundnes, 0.2);
}

TEST(Tissue, SheetConductionVelocityConvergesInSpace) {
  // Three spacings at a fixed small dt; observed order from the three CVs. The front across
  // the fibres is ~3x thinner (sigma ratio ~7.4), so its spacings are 2x finer.
  const double hs[3] = {0.2, 0.1, 0.05};
  double cv_f[3], cv_c[3];
  for (int k = 0; k < 3; ++k) {
    const auto o = seed_options(Formulation::kMonodomain, Splitting::kStrang, 0.01, "ttp06_epi");
    cv_f[k] = strip_cv(make_sheet(16.0, 0.4, hs[k], 0.0), o);
    cv_c[k] = strip_cv(make_sheet(8.0, 0.2, hs[k] / 2, 90.0), o);
    std::printf("sheet h = %.3f mm: CV along %.4f m/s | h = %.3f mm: CV across %.4f m/s\n", hs[k], cv_f[k],
                hs[k] / 2, cv_c[k]);
  }
  const double p_f = order(cv_f[0] - cv_f[1], cv_f[1] - cv_f[2], 2.0);
  const double p_c = order(cv_c[0] - cv_c[1], cv_c[1] - cv_c[2], 2.0);
  std::printf("observed order in h: along %.2f, across %.2f\n", p_f, p_c);
  // Nodal (operator-split) ionic currents with a consistent-mass diffusion: the CV error is
  // O(h) (coarse meshes overestimate CV; cf. Pathmanathan et al. 2011, Int J Numer Meth
  // Biomed Eng 27:1751). Asserted: at least first order, monotone from above.
  EXPECT_GT(p_f, 0.8);
  EXPECT_GT(p_c, 0.8);
  EXPECT_GT(cv_f[0], cv_f[1]);
  EXPECT_GT(cv_f[1], cv_f[2]);
  // Anisotropy: CV ratio ~ sqrt(sigma_f / sigma_c) of the harmonic-mean monodomain tensor.
  const Conductivity m = monodomain_conductivity({7.0, 0.8}, {25.0, 9.5});
  const double expect_ratio = std::sqrt(m.fibre_ms_per_cm / m.cross_ms_per_cm);
  std::printf("CV ratio along/across %.3f, sqrt(sigma ratio) %.3f\n", cv_f[2] / cv_c[2], expect_ratio);
  EXPECT_NEAR(cv_f[2] / cv_c[2] / expect_ratio, 1.0, 0.05);
}

TEST(Tissue, ConductionVelocityScalesWithSqrtSigma) {
  auto o = seed_options(Formulation::kMonodomain, Splitting::kStrang, 0.01, "ttp06_epi");
  const ElectroMesh mesh = make_sheet(16.0, 0.8, 0.1, 0.0);
  const double cv1 = strip_cv(mesh, o);
  o.sigma_i = {7.0 / 4, 0.8 / 4};
  o.sigma_e = {25.0 / 4, 9.5 / 4};
  const double cv4 = strip_cv(mesh, o);
  std::printf("CV(sigma) %.4f, CV(sigma/4) %.4f, ratio %.4f (sqrt: 2)\n", cv1, cv4, cv1 / cv4);
  // Exactly 2 in the continuum; the discretisation error at h = 0.1 mm is O(1 %).
  EXPECT_NEAR(cv1 / cv4, 2.0, 0.04);
}

TEST(Tissue, TimeStepConvergenceGodunovAndStrang) {
  const ElectroMesh mesh = make_sheet(16.0, 0.8, 0.2, 0.0);
  const double dts[3] = {0.08, 0.04, 0.02};
  for (Splitting sp : {Splitting::kGodunov, Splitting::kStrang}) {
    double cv[3];
    for (int k = 0; k < 3; ++k) cv[k] = strip_cv(mesh, seed_options(Formulation::kMonodomain, sp, dts[k], "aliev_panfilov"));
    const double p = order(cv[0] - cv[1], cv[1] - cv[2], 2.0);
    std::printf("%s: CV %.4f %.4f %.4f m/s at dt 0.08 0.04 0.02 ms, observed order %.2f\n",
                sp == Splitting::kGodunov ? "godunov" : "strang", cv[0], cv[1], cv[2], p);
    // Both are first order here: the reaction step is forward Euler in Vm (Strang's
    // second order needs a second-order reaction solver; ours: not done).
    EXPECT_GT(p, 0.7);
  }
}

TEST(Tissue, SlabConductionVelocityConverges) {
  const double hs[3] = {0.25, 0.125, 0.0625};
  double cv[3];
  for (int k = 0; k < 3; ++k) {
    cv[k] = strip_cv(make_slab(8.0, 0.25, 0.25, hs[k], 0.0),
                     seed_options(Formulation::kMonodomain, Splitting::kStrang, 0.01, "ttp06_epi"));
    std::printf("slab h = %.4f mm: CV along %.4f m/s\n", hs[k], cv[k]);
  }
  const double p = order(cv[0] - cv[1], cv[1] - cv[2], 2.0);
  std::printf("slab observed order in h: %.2f\n", p);
  EXPECT_GT(p, 0.8);
}

TEST(Tissue, BidomainEqualsMonodomainForProportionalTensors) {
  const ElectroMesh mesh = make_sheet(8.0, 4.0, 0.25, 30.0);
  for (Splitting sp : {Splitting::kGodunov, Splitting::kStrang}) {
    auto o = seed_options(Formulation::kMonodomain, sp, 0.02, "ttp06_epi");
    o.sigma_i = {7.0, 0.8};
    o.sigma_e = {2.5 * 7.0, 2.5 * 0.8};
    TissueSolver mono(mesh, o);
    o.formulation = Formulation::kBidomain;
    TissueSolver bi(mesh, o);
    double diff = 0, range = 0;
    for (int n = 0; n < 500; ++n) {
      mono.step();
      bi.step();
    }
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      diff = std::max(diff, std::abs(mono.vm_mv()[i] - bi.vm_mv()[i]));
      range = std::max(range, std::abs(mono.vm_mv()[i]));
    }
    std::printf("bidomain vs monodomain (%s, 10 ms): max |dVm| = %.3e mV\n",
                sp == Splitting::kGodunov ? "godunov" : "strang", diff);
    EXPECT_LT(diff, 1e-8 * range);
    // u_e = -v / (1 + lambda) + c for M_e = lambda M_i (here lambda = 2.5): u_e + v / 3.5 is
    // constant up to the solver tolerance.
    double lo = 1e300, hi = -1e300;
    for (std::size_t i = 0; i < mesh.node_count(); ++i) {
      const double c = bi.ue_mv()[i] + bi.vm_mv()[i] / 3.5;
      lo = std::min(lo, c);
      hi = std::max(hi, c);
    }
    std::printf("  u_e + v / (1 + lambda): spread %.3e mV\n", hi - lo);
    EXPECT_LT(hi - lo, 1e-8 * range);
    EXPECT_EQ(bi.diffusion_unknowns(), 2 * mono.diffusion_unknowns());
  }
}

TEST(Tissue, BadInputIsAClearError) {
  const ElectroMesh mesh = make_sheet(4.0, 4.0, 0.5, 0.0);
  auto base = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.02, "ttp06_epi");
  {
    auto o = base;
    o.domain_cell_models = {"ttp6"};
    try {
      TissueSolver s(mesh, o);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("known: aliev_panfilov"), std::string::npos) << e.what();
    }
  }
  {
    auto o = base;
    o.stimuli[0].region.box_min_mm = Vec3(50, 50, 50);
    o.stimuli[0].region.box_max_mm = Vec3(60, 60, 60);
    try {
      TissueSolver s(mesh, o);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("matches no node"), std::string::npos) << e.what();
    }
  }
  {
    auto o = base;
    o.sigma_i.fibre_ms_per_cm = 0.0;
    EXPECT_THROW(TissueSolver(mesh, o), InputError);
  }
  {
    auto o = base;
    o.dt_ms = 0.2;  // ttp06 declares 0.1 ms
    try {
      TissueSolver s(mesh, o);
      FAIL();
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("too large"), std::string::npos) << e.what();
    }
  }
}

TEST(Activation, ThresholdCrossingAndApd90AreInterpolated) {
  // One node resting at -80 mV: a linear upstroke to +20 mV, plateau, linear repolarisation.
  ActivationTracker tr({-80.0}, -40.0);
  auto v = [](double t) {
    if (t < 10) return -80.0;
    if (t < 11) return -80.0 + 100.0 * (t - 10);
    if (t < 200) return 20.0;
    if (t < 300) return 20.0 - (t - 200);
    return -80.0;
  };
  for (double t = 0; t < 400; t += 0.25) tr.update(t, {v(t)}, t + 0.25, {v(t + 0.25)});
  EXPECT_NEAR(tr.activation_ms()[0], 10.4, 1e-9);         // -40 mV crossed at t = 10.4
  EXPECT_NEAR(tr.repolarisation_ms()[0], 290.0, 1e-9);    // rest + 10 % of 100 mV = -70 mV
  EXPECT_NEAR(tr.apd_ms()[0], 279.6, 1e-9);
  tr.reset();
  EXPECT_TRUE(std::isnan(tr.activation_ms()[0]));
}

TEST(Stimulus, RegionsResolveToTheRightNodesAndPulsesRepeat) {
  ElectroMesh mesh = make_sheet(4.0, 4.0, 1.0, 0.0);  // nodes on the 1 mm grid, z = 0
  mesh.node_region[6] = 1u << 2;                       // one tagged node
  StimulusSpec spec{"s", {}, 10.0, 2.0, 5.0, 100.0};
  spec.region.kind = StimulusRegion::Kind::kSphere;
  spec.region.centre_mm = Vec3(2, 2, 0);
  spec.region.radius_mm = 1.01;  // centre + 4 neighbours
  EXPECT_EQ(Stimulus(mesh, spec).nodes().size(), 5u);
  spec.region.kind = StimulusRegion::Kind::kBox;
  spec.region.box_min_mm = Vec3(-0.5, -0.5, -1);
  spec.region.box_max_mm = Vec3(1.5, 0.5, 1);  // (0,0), (1,0)
  EXPECT_EQ(Stimulus(mesh, spec).nodes().size(), 2u);
  spec.region.kind = StimulusRegion::Kind::kTagged;
  spec.region.region_bits = 1u << 2;
  const Stimulus tagged(mesh, spec);
  ASSERT_EQ(tagged.nodes().size(), 1u);
  EXPECT_EQ(tagged.nodes()[0], 6);
  spec.region.domain = 1;  // no node of domain 1 on this mesh
  EXPECT_THROW(Stimulus(mesh, spec), InputError);
  spec.region.domain = -1;
  spec.region.kind = StimulusRegion::Kind::kNodes;
  spec.region.nodes = {3, 4, 99};  // 99 is not a node
  EXPECT_EQ(Stimulus(mesh, spec).nodes().size(), 2u);
  // Pulse train: start 5 ms, duration 2 ms, period 100 ms.
  EXPECT_EQ(tagged.amplitude_at(4.9), 0.0);
  EXPECT_EQ(tagged.amplitude_at(5.1), 10.0);
  EXPECT_EQ(tagged.amplitude_at(7.1), 0.0);
  EXPECT_EQ(tagged.amplitude_at(106.0), 10.0);
  spec.duration_ms = 0.0;
  EXPECT_THROW(Stimulus(mesh, spec), InputError);
}

TEST(Tissue, ActiveTensionRisesDuringTheActionPotentialAndRelaxes) {
  const ElectroMesh mesh = make_sheet(2.0, 2.0, 0.5, 0.0);
  auto o = seed_options(Formulation::kMonodomain, Splitting::kGodunov, 0.1, "aliev_panfilov");
  o.stimuli[0].region.box_max_mm = Vec3(10, 10, 10);
  TissueSolver s(mesh, o);
  double peak = 0, at_peak_time = 0;
  while (s.time_ms() < 900.0) {
    s.step();
    if (s.active_tension_kpa()[0] > peak) {
      peak = s.active_tension_kpa()[0];
      at_peak_time = s.time_ms();
    }
  }
  std::printf("tension peak %.2f kPa at %.0f ms, at 900 ms %.3f kPa\n", peak, at_peak_time,
              s.active_tension_kpa()[0]);
  EXPECT_GT(peak, 0.5 * o.tension_k_kpa);
  EXPECT_LE(peak, o.tension_k_kpa);
  EXPECT_GT(at_peak_time, 50.0);
  EXPECT_LT(s.active_tension_kpa()[0], 0.01 * peak);
}

}  // namespace
}  // namespace systole::electro
