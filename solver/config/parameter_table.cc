#include "solver/config/parameter_table.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>

namespace systole::config {
namespace {

// Each row's path is the member path in config::Scenario, stringified, so the table and the
// struct cannot drift apart; the proto is kept in step by tests/unit/config_proto_test.cc.
#define SYSTOLE_REAL(member, unit, def, lo, hi, doc)                                       \
  Param {                                                                                 \
    #member, Kind::kReal, unit, def, lo, hi, "", {}, doc,                                 \
        [](Scenario& s) -> double& { return s.member; }                                   \
  }
#define SYSTOLE_POSITIVE_REAL(member, unit, def, lo, hi, doc)                              \
  [] {                                                                                    \
    Param p = SYSTOLE_REAL(member, unit, def, lo, hi, doc);                               \
    p.min_exclusive = true;                                                               \
    return p;                                                                             \
  }()
#define SYSTOLE_INT(member, unit, def, lo, hi, doc)                                        \
  [] {                                                                                    \
    Param p{#member, Kind::kInt, unit, def, lo, hi, "", {}, doc};                         \
    p.integer = [](Scenario& s) -> int& { return s.member; };                             \
    return p;                                                                             \
  }()
#define SYSTOLE_BOOL(member, def, doc)                                                     \
  [] {                                                                                    \
    Param p{#member, Kind::kBool, "", (def) ? 1.0 : 0.0, 0, 1, "", {}, doc};              \
    p.boolean = [](Scenario& s) -> bool& { return s.member; };                            \
    return p;                                                                             \
  }()
#define SYSTOLE_CHOICE(member, def, choice_list, doc)                                      \
  [] {                                                                                    \
    Param p{#member, Kind::kChoice, "", 0, 0, 0, def, choice_list, doc};                  \
    p.choice = [](Scenario& s) -> std::string& { return s.member; };                      \
    return p;                                                                             \
  }()

std::vector<std::string_view> views(const std::vector<std::string>& names) {
  return {names.begin(), names.end()};
}

std::vector<Param> build_table() {
  const double inf = std::numeric_limits<double>::infinity();
  (void)inf;
  const std::vector<std::string_view> cell_models{"ttp06", "fhn", "aliev_panfilov",
                                                  "mitchell_schaeffer"};
  std::vector<Param> t;
  // --- run control ---------------------------------------------------------------------
  {
    Param p{"scene", Kind::kChoice, "", 0, 0, 0, "lumped", views(known_scenes()),
            "Which physics runs (the set of modules a scene assembles)."};
    p.choice = [](Scenario& s) -> std::string& { return s.scene; };
    t.push_back(p);
  }
  t.push_back(SYSTOLE_REAL(heart_rate_bpm, "1/min", 70, 20, 240,
                           "Heart rate; period = 60000 / heart_rate_bpm ms (seed: 70)."));
  t.push_back(SYSTOLE_INT(beats, "", 30, 1, 1000,
                          "Maximum beats to simulate; periodic-state detection may stop earlier."));
  t.push_back(SYSTOLE_REAL(av_delay_ms, "ms", 100, 0, 400,
                           "Atrio-ventricular delay from atrial to ventricular activation (seed)."));
  t.push_back(SYSTOLE_REAL(periodicity_tolerance, "", 1e-4, 0, 0.1,
                           "Stop when |EDV_n - EDV_{n-1}| / EDV_{n-1} falls below this; 0 runs all beats."));
  // --- tissue (eq 16-17, MODEL.md §5) ----------------------------------------------------
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.lv.fung_c_pa, "Pa", 13.3, 0, 1e5, "Fung c, LV."));
  t.push_back(SYSTOLE_REAL(tissue.lv.alpha_f, "", 49.56, 0, 1000, "Fung fibre exponent, LV."));
  t.push_back(SYSTOLE_REAL(tissue.lv.alpha_c, "", 5.29, 0, 1000, "Fung cross-fibre exponent, LV."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.la.fung_c_pa, "Pa", 12.1, 0, 1e5, "Fung c, LA."));
  t.push_back(SYSTOLE_REAL(tissue.la.alpha_f, "", 49.56, 0, 1000, "Fung fibre exponent, LA."));
  t.push_back(SYSTOLE_REAL(tissue.la.alpha_c, "", 5.29, 0, 1000, "Fung cross-fibre exponent, LA."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.mitral_leaflets.fung_c_pa, "Pa", 9.7, 0, 1e5,
                                    "Fung c, mitral leaflets."));
  t.push_back(SYSTOLE_REAL(tissue.mitral_leaflets.alpha_f, "", 49.56, 0, 1000,
                           "Fung fibre exponent, mitral leaflets."));
  t.push_back(SYSTOLE_REAL(tissue.mitral_leaflets.alpha_c, "", 5.29, 0, 1000,
                           "Fung cross-fibre exponent, mitral leaflets."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.aortic_leaflets.fung_c_pa, "Pa", 9.7, 0, 1e5,
                                    "Fung c, aortic cusps."));
  t.push_back(SYSTOLE_REAL(tissue.aortic_leaflets.alpha_f, "", 49.56, 0, 1000,
                           "Fung fibre exponent, aortic cusps."));
  t.push_back(SYSTOLE_REAL(tissue.aortic_leaflets.alpha_c, "", 5.29, 0, 1000,
                           "Fung cross-fibre exponent, aortic cusps."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.aorta.fung_c_pa, "Pa", 11.3, 0, 1e5, "Fung c, aorta."));
  t.push_back(SYSTOLE_REAL(tissue.aorta.alpha_f, "", 49.56, 0, 1000, "Fung fibre exponent, aorta."));
  t.push_back(SYSTOLE_REAL(tissue.aorta.alpha_c, "", 5.29, 0, 1000,
                           "Fung cross-fibre exponent, aorta."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.density_g_per_ml, "g/ml", 1.05, 0.5, 3,
                                    "Tissue density, every body (seed)."));
  t.push_back(SYSTOLE_REAL(tissue.poisson_ratio, "", 0.5, 0, 0.5,
                           "Poisson ratio nu_m in the bending stiffness (eq 19)."));
  t.push_back(SYSTOLE_REAL(tissue.active_tension_k_kpa, "kPa", 47.9, 0, 1000,
                           "Nash-Panfilov active tension amplitude k_tau (Nash & Panfilov 2004: "
                           "47.9 kPa); calibrated by the electromechanics scene."));
  // --- geometry variant (MODEL.md §1) ---------------------------------------------------
  t.push_back(SYSTOLE_REAL(geometry.lv_short_axis_mm, "mm", 58, 20, 120, "LV equatorial diameter."));
  t.push_back(SYSTOLE_REAL(geometry.lv_long_axis_mm, "mm", 75, 30, 140, "LV base-apex length."));
  t.push_back(SYSTOLE_REAL(geometry.lv_wall_mm, "mm", 8, 1, 30, "LV wall thickness."));
  t.push_back(SYSTOLE_REAL(geometry.lv_volume_ml, "ml", 125, 20, 400,
                           "LV stress-free cavity volume (closed by the valvular plane)."));
  t.push_back(SYSTOLE_REAL(geometry.la_volume_ml, "ml", 40, 5, 200, "LA stress-free cavity volume."));
  t.push_back(SYSTOLE_REAL(geometry.la_wall_mm, "mm", 4, 0.5, 15, "LA wall thickness."));
  t.push_back(SYSTOLE_REAL(geometry.mitral_diameter_mm, "mm", 24, 10, 50, "Mitral orifice diameter d_m."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_diameter_mm, "mm", 19, 8, 40, "Aortic orifice diameter d_a."));
  t.push_back(SYSTOLE_REAL(geometry.mitral_leaflet_length_mm, "mm", 20, 5, 40,
                           "Anterior mitral leaflet length, annulus to free edge (ours)."));
  t.push_back(SYSTOLE_REAL(geometry.mitral_leaflet_thickness_mm, "mm", 2, 0.2, 6,
                           "Mitral leaflet thickness."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_leaflet_thickness_mm, "mm", 1.5, 0.2, 6,
                           "Aortic cusp thickness."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_root_diameter_mm, "mm", 40, 15, 70, "Aortic root diameter."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_arch_diameter_mm, "mm", 30, 10, 60, "Aortic arch diameter."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_descending_diameter_mm, "mm", 22, 8, 50,
                           "Thoracic descending aorta diameter."));
  t.push_back(SYSTOLE_REAL(geometry.aorta_wall_mm, "mm", 3, 0.5, 10, "Aortic wall thickness."));
  t.push_back(SYSTOLE_REAL(geometry.pulmonary_vein_diameter_mm, "mm", 10, 3, 25,
                           "Pulmonary-vein ostium diameter (4 ostia)."));
  t.push_back(SYSTOLE_REAL(geometry.lv_fibre_angle_deg, "deg", 45, -90, 90,
                           "LV fibre helix angle (counter-clockwise from apex to base)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(geometry.target_edge_mm, "mm", 2, 0.1, 20,
                                    "Target edge length of the base surface mesh (ours)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(geometry.marker_spacing_fraction, "", 0.7, 0.1, 2,
                                    "Lagrangian marker spacing / Eulerian spacing (quadratic tiling)."));
  // --- electrophysiology (eq 21-23, MODEL.md §6) -----------------------------------------
  t.push_back(SYSTOLE_CHOICE(electro.model, "bidomain",
                             (std::vector<std::string_view>{"bidomain", "monodomain"}),
                             "Bidomain (seed) or monodomain."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.surface_to_volume_per_cm, "1/cm", 1400, 1, 1e5,
                                    "Membrane surface-to-volume ratio chi."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.membrane_capacitance_uf_per_cm2, "uF/cm^2", 1, 0.01, 100,
                                    "Membrane capacitance C_m."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.sigma_e_fibre_ms_per_cm, "mS/cm", 25.0, 0, 1000,
                                    "Extracellular conductivity along the fibre."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.sigma_e_cross_ms_per_cm, "mS/cm", 9.5, 0, 1000,
                                    "Extracellular conductivity across the fibre."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.sigma_i_fibre_ms_per_cm, "mS/cm", 7.0, 0, 1000,
                                    "Intracellular conductivity along the fibre."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.sigma_i_cross_ms_per_cm, "mS/cm", 0.8, 0, 1000,
                                    "Intracellular conductivity across the fibre."));
  {
    Param p = SYSTOLE_CHOICE(electro.lv_cell_model, "ttp06",
                             (std::vector<std::string_view>{}), "Ventricular cell model.");
    p.choices = cell_models;
    t.push_back(p);
    Param q = SYSTOLE_CHOICE(electro.la_cell_model, "fhn",
                             (std::vector<std::string_view>{}), "Atrial cell model.");
    q.choices = cell_models;
    t.push_back(q);
  }
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.stimulus.duration_ms, "ms", 2, 0, 50,
                                    "Stimulus duration (Bachmann bundle, His bundle)."));
  t.push_back(SYSTOLE_REAL(electro.stimulus.amplitude_ua_per_cm2, "uA/cm^2", 35, 0, 1000,
                           "Stimulus amplitude."));
  // --- fluid (eq 1-10, MODEL.md §3) ------------------------------------------------------
  t.push_back(SYSTOLE_REAL(fluid.kinematic_viscosity_m2_per_s, "m^2/s", 4.8e-6, 1e-8, 0.1,
                           "Newtonian kinematic viscosity; Re = U_m d_m / nu = 0.0144 m^2/s / nu (seed blood "
                           "4.8e-6: Re = 3000). Values above ~1e-5 are not blood: they reach the low-Re "
                           "verification flows of scene 'fluid' (Re = 10 at 1.44e-3, Re = 100 at 1.44e-4)."));
  t.push_back(SYSTOLE_CHOICE(fluid.viscosity_model, "newtonian",
                             (std::vector<std::string_view>{"newtonian", "carreau_yasuda"}),
                             "Newtonian (seed) or Carreau-Yasuda shear thinning."));
  t.push_back(SYSTOLE_INT(fluid.nx, "", 129, 8, 2049, "Grid points in x (grid 1 of Table 1)."));
  t.push_back(SYSTOLE_INT(fluid.ny, "", 129, 8, 2049, "Grid points in y."));
  t.push_back(SYSTOLE_INT(fluid.nz, "", 145, 8, 2049, "Grid points in z."));
  t.push_back(SYSTOLE_REAL(fluid.box_x_mm, "mm", 95, 10, 1000, "Fluid box size in x (periodic)."));
  t.push_back(SYSTOLE_REAL(fluid.box_y_mm, "mm", 95, 10, 1000, "Fluid box size in y (periodic)."));
  t.push_back(SYSTOLE_REAL(fluid.box_z_mm, "mm", 140, 10, 1000, "Fluid box size in z (no-slip walls)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.cfl, "", 0.2, 0, 1, "Target CFL number."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.max_dt_ms, "ms", 0.1, 0, 10, "Largest fluid time step."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.darcy_permeability, "", 0.001, 0, 1,
                                    "Darcy afterload permeability k, nondimensional (seed 0.001)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.carreau_yasuda_mu0_pa_s, "Pa*s", 0.056, 0, 10,
                                    "Carreau-Yasuda zero-shear viscosity mu0 in mu = mu_inf + (mu0 - mu_inf) "
                                    "[1 + (lambda gamma_dot)^a]^((n-1)/a); blood: Cho & Kensey 1991."));
  t.push_back(SYSTOLE_REAL(fluid.carreau_yasuda_mu_inf_pa_s, "Pa*s", 0.00345, 0, 10,
                           "Carreau-Yasuda infinite-shear viscosity mu_inf (<= mu0); blood: Cho & Kensey 1991."));
  t.push_back(SYSTOLE_REAL(fluid.carreau_yasuda_lambda_s, "s", 3.313, 0, 1000,
                           "Carreau-Yasuda time constant lambda; blood: Cho & Kensey 1991."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.carreau_yasuda_n, "", 0.3568, 0, 1,
                                    "Carreau-Yasuda power-law index n (shear thinning; 1 is Newtonian); blood: "
                                    "Cho & Kensey 1991."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.carreau_yasuda_a, "", 2, 0, 10,
                                    "Carreau-Yasuda transition exponent a (2: the Carreau law of Cho & Kensey)."));
  t.push_back(SYSTOLE_REAL(fluid.density_kg_per_m3, "kg/m^3", 1060, 500, 3000,
                           "Blood density; converts the Carreau-Yasuda viscosities to nu = mu / rho "
                           "(nondimensional nu* = mu / (rho U_m d_m)). Not used by the Newtonian model."));
  t.push_back(SYSTOLE_CHOICE(fluid.verification_case, "taylor_green_2d",
                             (std::vector<std::string_view>{"taylor_green_2d", "poiseuille", "couette", "womersley",
                                                            "taylor_green_3d"}),
                             "Scene 'fluid': the verification flow (solver/fluid/verification_cases.h). Each case "
                             "fixes its own box and walls; box_*_mm are not used; nx, ny, nz are points "
                             "(cells + 1)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.end_time_ms, "ms", 40, 0, 1e7,
                                    "Scene 'fluid': simulated time (40 ms = one d_m / U_m). Samples of the time "
                                    "series every outputs.time_series_interval_ms."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.womersley_number, "", 4, 0, 100,
                                    "Scene 'fluid', womersley case: Wo = (L_z/2) sqrt(omega Re) of the oscillating "
                                    "pressure gradient."));
  t.push_back(SYSTOLE_BOOL(fluid.write_fields, false,
                           "Scene 'fluid': write velocity, pressure and vorticity at the end (HDF5 + XDMF, "
                           "fluid_fields.h5/.xmf in the output directory); outputs.fields selects a subset."));
  // --- 0-D circulation (solver/lumped/README.md) -----------------------------------------
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.lv.emax_mmhg_per_ml, "mmHg/ml", 2.7, 0, 50,
                                    "LV peak (end-systolic) elastance Emax in E(t) = Emin + "
                                    "(Emax - Emin) a(t) (Suga-Sagawa); calibrated for EF ~58 % "
                                    "(solver/lumped/README.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.lv.emin_mmhg_per_ml, "mmHg/ml", 0.07, 0, 5,
                                    "LV passive elastance Emin (linear EDPVR; EDP ~8 mmHg at "
                                    "EDV 125 ml)."));
  t.push_back(SYSTOLE_REAL(lumped.lv.v0_ml, "ml", 10, 0, 200,
                           "LV unstressed volume V0: P = E(t) (V - V0)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.lv.contraction_ms, "ms", 290, 0, 1000,
                                    "LV activation raised-cosine rise to Emax, at 70 bpm (scaled by "
                                    "sqrt(period / 857 ms)); sets aortic closure near t/T 0.35."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.lv.relaxation_ms, "ms", 80, 0, 1000,
                                    "LV activation raised-cosine fall, at 70 bpm (scaled likewise); sets "
                                    "mitral opening near t/T 0.42."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.la.emax_mmhg_per_ml, "mmHg/ml", 0.5, 0, 50,
                                    "LA peak elastance (atrial kick; E/A ~1.6)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.la.emin_mmhg_per_ml, "mmHg/ml", 0.15, 0, 5,
                                    "LA passive elastance."));
  t.push_back(SYSTOLE_REAL(lumped.la.v0_ml, "ml", 4, 0, 200, "LA unstressed volume."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.la.contraction_ms, "ms", 100, 0, 1000,
                                    "LA activation rise, starting av_delay_ms before the LV's, "
                                    "at 70 bpm."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.la.relaxation_ms, "ms", 100, 0, 1000,
                                    "LA activation fall, at 70 bpm."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.mitral_resistance_mmhg_s_per_ml, "mmHg*s/ml", 0.005,
                                    0, 10,
                                    "Open mitral valve resistance (smooth diode law, "
                                    "solver/lumped/valve.h)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.aortic_resistance_mmhg_s_per_ml, "mmHg*s/ml", 0.005,
                                    0, 10, "Open aortic valve resistance (in series with Zc)."));
  t.push_back(SYSTOLE_REAL(lumped.mitral_inertance_mmhg_s2_per_ml, "mmHg*s^2/ml", 0, 0, 1,
                           "Mitral inertance; > 0 makes the valve flow a state (0: none). "
                           "Must be 0 when the LV or LA is an external (3-D) chamber."));
  t.push_back(SYSTOLE_REAL(lumped.aortic_inertance_mmhg_s2_per_ml, "mmHg*s^2/ml", 0, 0, 1,
                           "Aortic inertance; > 0 makes the valve flow a state (0: none). "
                           "Must be 0 when the LV is an external (3-D) chamber."));
  t.push_back(SYSTOLE_REAL(lumped.valve_backflow_conductance_fraction, "", 1e-5, 0, 0.1,
                           "Closed-valve conductance as a fraction of the open one (leak); must be "
                           "> 0 with external chambers."));
  t.push_back(SYSTOLE_REAL(lumped.aortic_characteristic_impedance_mmhg_s_per_ml, "mmHg*s/ml",
                           0.035, 0, 10,
                           "Three-element Windkessel characteristic impedance Zc (aortic root "
                           "to C)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.systemic_resistance_mmhg_s_per_ml, "mmHg*s/ml", 1.05, 0,
                                    20,
                                    "Windkessel peripheral resistance R, into the pulmonary "
                                    "venous compliance."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.systemic_compliance_ml_per_mmhg, "ml/mmHg", 1.8, 0, 20,
                                    "Windkessel total arterial compliance C."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.pulmonary_venous_compliance_ml_per_mmhg, "ml/mmHg", 10,
                                    0, 200, "Pulmonary venous compliance (the loop's return)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.pulmonary_venous_resistance_mmhg_s_per_ml, "mmHg*s/ml",
                                    0.02, 0, 10, "Pulmonary venous resistance into the LA."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.stressed_blood_volume_ml, "ml", 372, 0, 5000,
                                    "Stressed blood volume: sum of (V - V0) of LV and LA plus "
                                    "C P of both compliances; sets the filling (EDV 125 ml)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(lumped.time_step_ms, "ms", 0.5, 0, 10,
                                    "0-D RK4 step (largest; steps also end on activation "
                                    "breakpoints). 0.5 ms: metrics within 2e-3 mmHg of a "
                                    "converged run."));
  // --- coupling (MODEL.md §7) -------------------------------------------------------------
  t.push_back(SYSTOLE_CHOICE(coupling.mode, "loose",
                             (std::vector<std::string_view>{"loose", "strong"}),
                             "Loose (seed production runs) or strong (iterated) coupling."));
  t.push_back(SYSTOLE_POSITIVE_REAL(coupling.strong_tolerance, "", 1e-4, 0, 0.1,
                                    "Strong coupling: relative change of positions and velocities."));
  t.push_back(SYSTOLE_INT(coupling.strong_max_iterations, "", 4, 1, 50,
                          "Strong coupling: most iterations per step."));
  // --- outputs ---------------------------------------------------------------------------
  t.push_back(SYSTOLE_BOOL(outputs.metrics, true, "Write per-beat metrics."));
  t.push_back(SYSTOLE_BOOL(outputs.time_series, true, "Write pressure/volume/flow time series."));
  t.push_back(SYSTOLE_POSITIVE_REAL(outputs.time_series_interval_ms, "ms", 1, 0.01, 1000,
                                    "Time-series sampling interval."));
  t.push_back(SYSTOLE_INT(outputs.time_series_last_beats, "", 1, 0, 1000,
                          "Keep only the last N beats in the time series (0: all)."));
  {
    Param p{"outputs.fields", Kind::kChoiceList, "", 0, 0, 0, "",
            {"velocity", "pressure", "vorticity", "vm", "displacement", "wss"},
            "3-D fields to write, for scenes that have them."};
    p.choice_list = [](Scenario& s) -> std::vector<std::string>& { return s.outputs.fields; };
    t.push_back(p);
    Param q{"outputs.field_phases", Kind::kRealList, "", 0, 0, 1, "", {},
            "Phases t/T in [0, 1) at which fields are written."};
    q.real_list = [](Scenario& s) -> std::vector<double>& { return s.outputs.field_phases; };
    q.max_exclusive = true;
    t.push_back(q);
  }
  // --- analytic test functions (scene "analytic") ----------------------------------------
  t.push_back(SYSTOLE_CHOICE(analytic.function, "ishigami", (std::vector<std::string_view>{"ishigami"}),
                             "Closed-form test function of scene 'analytic' (Ishigami & Homma 1990)."));
  t.push_back(SYSTOLE_REAL(analytic.x1, "", 0, -10, 10, "Input x1 (Ishigami: uniform on [-pi, pi] in the benchmark)."));
  t.push_back(SYSTOLE_REAL(analytic.x2, "", 0, -10, 10, "Input x2."));
  t.push_back(SYSTOLE_REAL(analytic.x3, "", 0, -10, 10, "Input x3."));
  t.push_back(SYSTOLE_REAL(analytic.a, "", 7, -100, 100, "Ishigami a (benchmark value 7)."));
  t.push_back(SYSTOLE_REAL(analytic.b, "", 0.1, -100, 100, "Ishigami b (benchmark value 0.1)."));
  return t;
}

#undef SYSTOLE_REAL
#undef SYSTOLE_POSITIVE_REAL
#undef SYSTOLE_INT
#undef SYSTOLE_BOOL
#undef SYSTOLE_CHOICE

std::string format_number(double v) {
  std::ostringstream out;
  out << v;
  return out.str();
}

}  // namespace

const std::vector<Param>& parameter_table() {
  static const std::vector<Param> table = build_table();  // immutable after construction
  return table;
}

const Param* find_parameter(std::string_view path) {
  static const std::unordered_map<std::string_view, const Param*> index = [] {
    std::unordered_map<std::string_view, const Param*> m;
    for (const Param& p : parameter_table()) m.emplace(p.path, &p);
    return m;
  }();
  auto it = index.find(path);
  return it == index.end() ? nullptr : it->second;
}

std::string describe_allowed(const Param& p) {
  std::ostringstream out;
  switch (p.kind) {
    case Kind::kReal:
    case Kind::kRealList:
    case Kind::kInt:
      out << (p.min_exclusive ? "(" : "[") << format_number(p.min) << ", " << format_number(p.max)
          << (p.max_exclusive ? ")" : "]");
      if (p.kind == Kind::kInt) out << " (integer)";
      if (p.kind == Kind::kRealList) out << " (each element of a list)";
      break;
    case Kind::kBool:
      out << "true or false";
      break;
    case Kind::kChoice:
    case Kind::kChoiceList: {
      out << "one of: ";
      for (size_t i = 0; i < p.choices.size(); ++i) out << (i ? ", " : "") << p.choices[i];
      if (p.kind == Kind::kChoiceList) out << " (each element of a list)";
      break;
    }
  }
  return out.str();
}

std::string parameters_markdown() {
  std::ostringstream out;
  out << "# Scenario parameters\n\n"
      << "Generated by `systole-solve --list-parameters` from solver/config/parameter_table.cc; "
         "do not edit by hand.\nDefaults are the seed's healthy left heart at 70 bpm "
         "(../shared/MODEL.md).\n\n"
      << "| field | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const Param& p : parameter_table()) {
    std::string def;
    switch (p.kind) {
      case Kind::kReal:
      case Kind::kInt: def = format_number(p.default_number); break;
      case Kind::kBool: def = p.default_number != 0 ? "true" : "false"; break;
      case Kind::kChoice: def = std::string(p.default_choice); break;
      case Kind::kRealList:
      case Kind::kChoiceList: def = "[]"; break;
    }
    out << "| `" << p.path << "` | " << (p.unit.empty() ? "-" : std::string(p.unit)) << " | " << def
        << " | " << describe_allowed(p) << " | " << p.doc << " |\n";
  }
  return out.str();
}

}  // namespace systole::config
