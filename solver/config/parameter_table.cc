#include "solver/config/parameter_table.h"

#include <cmath>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "solver/config/removed_fields.h"

namespace systole::config {
namespace {

// The in-plane spring laws of solver/structure/spring_law.h (structure.law and
// electromechanics.spring_law choose among the same registry).
const std::vector<std::string_view>& spring_law_names() {
  static const std::vector<std::string_view> names{"fung", "linear", "neo_hookean", "fung_tension"};
  return names;
}

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
#define SYSTOLE_STRING(member, def, doc)                                                   \
  [] {                                                                                    \
    Param p{#member, Kind::kString, "", 0, 0, 0, def, {}, doc};                           \
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
                                                  "mitchell_schaeffer", "ttp06_endo", "ttp06_mid",
                                                  "ttp06_epi", "fhn_atrial"};
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
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.mitral_leaflets.fung_c_pa, "Pa", 3702, 0, 1e5,
                                    "Fung c, mitral leaflets (ours: the seed's 9.7 read in units of rho U^2 = 381.6 Pa; "
                                    "with 9.7 Pa the closed valves tear or invert under the aortic and LV "
                                    "pressures, docs/fsei.md)."));
  t.push_back(SYSTOLE_REAL(tissue.mitral_leaflets.alpha_f, "", 49.56, 0, 1000,
                           "Fung fibre exponent, mitral leaflets."));
  t.push_back(SYSTOLE_REAL(tissue.mitral_leaflets.alpha_c, "", 5.29, 0, 1000,
                           "Fung cross-fibre exponent, mitral leaflets."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.aortic_leaflets.fung_c_pa, "Pa", 3702, 0, 1e5,
                                    "Fung c, aortic cusps (ours: the seed's 9.7 read in units of rho U^2 = 381.6 Pa; "
                                    "with 9.7 Pa the closed valves tear or invert under the aortic and LV "
                                    "pressures, docs/fsei.md)."));
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
  t.push_back(SYSTOLE_REAL(tissue.active_tension_k_kpa, "kPa", 340, 0, 1000,
                           "Nash-Panfilov active tension amplitude k_tau (Nash & Panfilov 2004: "
                           "47.9 kPa); 340 calibrated by the electromechanics scene against its 0-D afterload "
                           "(docs/electromechanics.md); scene fsei in blood: 250, at which the LV no longer reaches 170 mmHg by 0.16 T (docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(tissue.active_tension_time_scale_ms, "ms", 20, 0, 1000,
                                    "Nash-Panfilov time unit t_scale (eq 23): the tension rises with time constant "
                                    "10 t_scale and relaxes with t_scale (Nash & Panfilov 2004: 12.9 ms; 20 ms "
                                    "calibrated by the electromechanics scene, ours)."));
  t.push_back(SYSTOLE_REAL(tissue.active_min_fibre_stretch, "", 0.5, 0, 0.99,
                           "Length-tension relation of the active fibre stress (ours): the tension is "
                           "tau f(lambda), f = 1 - ((1 - lambda)/(1 - m))^2 between this stretch m and 1, 0 below "
                           "m, 1 above 1; 0: no length dependence (the seed's eq 24)."));
  t.push_back(SYSTOLE_REAL(tissue.active_cross_fibre_fraction, "", 0.5, 0, 1,
                           "Cross-fibre active stress as a fraction of the fibre stress (ours; a membrane "
                           "stand-in for the transmural fibre rotation of the real wall); 0: fibre only (the seed's)."));
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
  t.push_back(SYSTOLE_REAL(geometry.valve_gap_mm, "mm", 0, 0, 3,
                           "Gap between the free edges of the neighbouring closed mitral leaflets and aortic cusps "
                           "(ours): 0 gives one orifice-ring edge (the free edges end on ring nodes, about "
                           "target_edge_mm); else it must be shorter than a ring edge (docs/geometry.md)."));
  t.push_back(SYSTOLE_REAL(geometry.aortic_commissure_height_per_radius, "-", 0.8, 0, 2,
                           "Height of the aortic commissures above the valvular plane, over the aortic orifice "
                           "radius (ours): the cusps hang from a crown-shaped attachment on the root wall, fibres "
                           "from commissure to commissure, with vertical coaptation strips; at least 0.6 (the "
                           "closed cusps' tips are at 0.5). 0 gives the flat-annulus cusps of the first "
                           "coupled runs, which do not carry the aortic pressure (docs/geometry.md, docs/fsei.md)."));
  t.push_back(SYSTOLE_REAL(geometry.darcy_region_length_per_diameter, "-", 1.5, 0.25, 20,
                           "Length of the Darcy outflow region (scenes 'fsi'/'fsei': the sink -u/k of "
                           "fluid.darcy_permeability) at the end of the thoracic descending aorta, in descending-aorta "
                           "diameters (ours: the seed places it near the aorta's end without a length). The region must "
                           "lie in the descending aorta's straight tube: below the taper from the arch's diameter "
                           "(2 descending diameters) and one radius more (the descending-aorta probe); a longer one "
                           "is refused with the largest allowed (docs/fsei.md)."));
  t.push_back(SYSTOLE_REAL(geometry.mitral_rest_opening_mm, "mm", 0, 0, 20,
                           "Opening of the mitral leaflets' stress-free (rest) shape, between the middles of their free "
                           "edges (ours): the leaflets are built closed (their initial shape, and the mitral limiter's "
                           "reference) over a rest shape whose free edges and coaptation strips are moved apart by this "
                           "much at the middle (opening/2 (1 - s^2) each, s from commissure to commissure), the leaflet "
                           "length kept; so the closed valve is pre-strained and opens wider at a small pressure "
                           "(docs/geometry.md, docs/notes/fsei-notebook.md). Each rest free edge's middle must stay within "
                           "3/4 of the mitral radius from the orifice's centre (valve_gap_mm / 2 + opening / 2 <= "
                           "0.75 mitral_diameter_mm / 2: 17 mm at the defaults' gap 1 mm). 0: the leaflets are "
                           "stress-free closed (the first geometry)."));
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
    Param q = SYSTOLE_CHOICE(electro.la_cell_model, "fhn_atrial",
                             (std::vector<std::string_view>{}),
                             "Atrial cell model (fhn_atrial, ours: FitzHugh-Nagumo with a 30x faster Vm "
                             "equation, CV ~0.9 m/s at the seed's conductivities; fhn: the Sundnes et al. "
                             "set, ~0.13 m/s).");
    q.choices = cell_models;
    t.push_back(q);
  }
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.stimulus.duration_ms, "ms", 2, 0, 50,
                                    "Stimulus duration (Bachmann bundle, His bundle)."));
  t.push_back(SYSTOLE_REAL(electro.stimulus.amplitude_ua_per_cm2, "uA/cm^2", 35, 0, 1000,
                           "Stimulus amplitude."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.stimulus.box_size_mm, "mm", 1.5, 0, 1000,
                                    "Scene 'electro', sheet/slab meshes: edge of the cubic stimulus box at the "
                                    "origin corner (Niederer et al. 2011: 1.5 mm)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.time_step_ms, "ms", 0.05, 0, 1,
                                    "Electrophysiology time step (reaction and diffusion); must not exceed the "
                                    "cell models' largest stable step (ttp06 0.1 ms, mitchell_schaeffer 0.1 ms)."));
  t.push_back(SYSTOLE_CHOICE(electro.splitting, "godunov",
                             (std::vector<std::string_view>{"godunov", "strang"}),
                             "Operator splitting: godunov (reaction, then backward-Euler diffusion) or strang "
                             "(half Crank-Nicolson diffusion, reaction, half diffusion)."));
  t.push_back(SYSTOLE_CHOICE(electro.mesh, "left_heart",
                             (std::vector<std::string_view>{"left_heart", "sheet", "slab", "manifest"}),
                             "Scene 'electro': the procedural left heart (LV + LA walls, triangles), a flat "
                             "sheet of triangles, a box slab of tetrahedra (electro.mesh_*), or an imported "
                             "heart (electro.mesh_manifest)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.mesh_size_x_mm, "mm", 20, 0, 1000,
                                    "Sheet/slab size in x (Niederer et al. 2011 slab: 20 x 7 x 3 mm)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.mesh_size_y_mm, "mm", 7, 0, 1000, "Sheet/slab size in y."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.mesh_size_z_mm, "mm", 3, 0, 1000, "Slab size in z (not used by the sheet)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.mesh_spacing_mm, "mm", 0.5, 0, 100, "Sheet/slab node spacing."));
  t.push_back(SYSTOLE_REAL(electro.fibre_angle_deg, "deg", 0, -180, 180,
                           "Sheet/slab fibre direction, angle from +x in the x-y plane."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.end_time_ms, "ms", 60, 0, 1e6,
                                    "Scene 'electro', sheet/slab: simulated time (the left heart runs `beats` "
                                    "periods of the heart rate)."));
  t.push_back(SYSTOLE_REAL(electro.activation_threshold_mv, "mV", -40, -100, 50,
                           "Activation time: upward crossing of this potential (ours)."));
  t.push_back(SYSTOLE_BOOL(electro.purkinje, true,
                           "Scene 'electro', left heart: Purkinje surrogate (ours) - besides the His bundle, "
                           "electro.purkinje_sites early-activation stimuli spread over the LV, each delayed by "
                           "its straight-line distance from the His site / purkinje_conduction_velocity_m_per_s. "
                           "false: the His bundle alone."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.purkinje_conduction_velocity_m_per_s, "m/s", 2, 0, 100,
                                    "Purkinje surrogate: conduction velocity of the Purkinje network (1-4 m/s)."));
  t.push_back(SYSTOLE_INT(electro.purkinje_sites, "", 16, 1, 1000,
                          "Purkinje surrogate: number of LV sites (farthest-point sampling from the His site)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electro.la_conductivity_scale, "", 1, 0, 1000,
                                    "Left heart: factor on sigma_i and sigma_e in the LA (ours; the FHN parameter "
                                    "set conducts at ~0.17 m/s with the seed's conductivities, CV ~ sqrt(factor); a factor >= 4 "
                                    "stops the default Bachmann stimulus from exciting, docs/electro.md)."));
  t.push_back(SYSTOLE_INT(electro.threads, "", 1, 1, 256,
                          "OpenMP threads of the cell-model (reaction) step; the diffusion solve is serial. "
                          "Every MPI rank runs the whole EP solve with this many threads."));
  t.push_back(SYSTOLE_STRING(electro.mesh_manifest, "",
                             "Scene 'electro', mesh = manifest: path of a mesh manifest (JSON, "
                             "geometry::load_manifest) on the machine that runs the solver; relative paths "
                             "are resolved against the solver's working directory. It must describe an LV "
                             "and/or an LA body (names 'lv', 'la')."));
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
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.cfl, "", 0.2, 0, 1,
                                    "Target CFL number (not part of an fsi/fsei checkpoint's fingerprint: a run stopped "
                                    "by the fluid's CFL or energy guard resumes at a smaller one)."));
  t.push_back(SYSTOLE_CHOICE(fluid.cfl_rule, "component_maxima",
                             (std::vector<std::string_view>{"component_maxima", "per_cell"}),
                             "Scenes 'fsi'/'fsei': how the step's CFL number is measured. component_maxima (ours, "
                             "conservative): dt (max abs(u)/dx + max abs(v)/dy + max abs(w)/dz), each maximum over the "
                             "whole field; per_cell: dt max over cells of (abs(u)/dx + abs(v)/dy + abs(w)/dz), the "
                             "local form of "
                             "the seed's codes (AFiD's CalcMaxCFL), larger steps when the fastest flows of the "
                             "three directions lie in different places. Not part of a checkpoint's fingerprint."));
  t.push_back(SYSTOLE_CHOICE(fluid.subgrid_model, "none", (std::vector<std::string_view>{"none", "vreman"}),
                             "Scenes 'fluid'/'fsi'/'fsei': subgrid eddy viscosity (ours; the seed's runs are DNS). "
                             "none: the seed's; vreman: Vreman's model (Phys. Fluids 16, 2004), nu = 1/Re + "
                             "c sqrt(B_beta / (alpha_ij alpha_ij)) from the resolved velocity gradient, zero in "
                             "any unidirectional shear flow, O(dx^2) on smooth flows; it damps the grid-scale "
                             "velocity of an under-resolved jet (docs/notes/fsei-notebook.md). Newtonian only."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.subgrid_constant, "", 0.07, 0, 1,
                                    "Vreman's constant c (fluid.subgrid_model = vreman); c = 2.5 Cs^2 with the "
                                    "Smagorinsky constant Cs (0.07: Cs = 0.17)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.max_dt_ms, "ms", 0.1, 0, 10, "Largest fluid time step."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fluid.darcy_permeability, "", 0.001, 0, 1,
                                    "Darcy afterload permeability k, nondimensional (seed 0.001). In scenes 'fsi'/'fsei' "
                                    "the region is the aorta's last 1.5 diameters: Darcy's law over it gives 0.0173/k "
                                    "mmHg s/ml (17 at 0.001, 15x a human's ~1.1); measured in the heart: 6.8 at 0.001 "
                                    "with MLS's leaky walls, 1.2-1.4 at 0.016 in the tight setting ("
                                    "docs/notes/fsei-notebook.md)."));
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
                           0.025, 0, 10,
                           "Three-element Windkessel characteristic impedance Zc (aortic root "
                           "to C); 0.025 chosen with the electromechanics scene (solver/lumped/README.md)."));
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
  t.push_back(SYSTOLE_CHOICE(coupling.mode, "strong",
                             (std::vector<std::string_view>{"loose", "strong"}),
                             "Loose (one pass per synchronisation step, the seed's production runs) or strong "
                             "(iterated). Scene 'electromechanics': the cavity-volume constraint needs strong "
                             "(loose blew up in the first beat, docs/electromechanics.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(coupling.strong_tolerance, "", 1e-4, 0, 0.1,
                                    "Strong coupling: relative change of the transferred data between passes."));
  t.push_back(SYSTOLE_INT(coupling.strong_max_iterations, "", 4, 1, 50,
                          "Strong coupling: most iterations per step."));
  t.push_back(SYSTOLE_CHOICE(coupling.relaxation, "aitken",
                             (std::vector<std::string_view>{"aitken", "iqn_ils", "constant", "none"}),
                             "Scenes fsi/fsei, strong coupling: how the hydrodynamic loads are relaxed between "
                             "passes: Aitken's dynamic factor, interface quasi-Newton IQN-ILS (secant columns "
                             "reused across intervals), a constant factor 0.5, or none (docs/fsei.md)."));
  t.push_back(SYSTOLE_INT(coupling.iqn_reuse_intervals, "", 8, 0, 100,
                          "Scenes fsi/fsei, relaxation iqn_ils: earlier synchronisation intervals whose "
                          "secant columns are reused (0: this interval's only)."));
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
  // --- structure and scene "mechanics" (solver/structure/README.md) ---------------------
  t.push_back(SYSTOLE_CHOICE(structure.law, "fung",
                             spring_law_names(),
                             "In-plane spring law of every tissue (eq 17 'fung'; 'linear', 'neo_hookean' and "
                             "'fung_tension' share its small-strain modulus c alpha; 'fung_tension', ours: the Fung "
                             "exponential in tension only, capped at structure.fung_exponent_cap, linear in "
                             "compression)."));
  t.push_back(SYSTOLE_CHOICE(structure.membrane, "springs", (std::vector<std::string_view>{"springs", "triangles"}),
                             "In-plane model of every shell: 'springs' (eq 17-18, one Fung spring per edge) or "
                             "'triangles' (ours: a constant-strain membrane triangle with eq 16's energy in eq 17's strain "
                             "along its fibre and cross-fibre directions plus a shear term alpha_c gamma^2 / 2; takes "
                             "structure.law = "
                             "'fung' and, for the chamber walls, electromechanics.spring_law = 'fung'; "
                             "docs/structure.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.fung_exponent_cap, "", 4, 0, 100,
                                    "Law 'fung_tension': the largest Fung exponent alpha eps^2; beyond it the stress "
                                    "grows linearly with the tangent there (ours; bounds the explicit stable step)."));
  t.push_back(SYSTOLE_REAL(structure.fung_compression_fraction, "", 0.008, 0, 1,
                           "Law 'fung_tension': in compression the stress is c alpha eps plus this fraction of the "
                           "capped Fung law's stiffening (ours; 0: linear, 1: the capped Fung law both ways)."));
  t.push_back(SYSTOLE_REAL(structure.area_floor, "", 0, 0, 0.95,
                           "Area floor of every shell triangle (ours; 0: off, the seed's springs only): below this "
                           "ratio J of its stress-free area a triangle resists with the energy kappa s A0 (J0 - J)^2 / J, "
                           "which grows without bound as J -> 0, so the triangle cannot be squeezed flat in its plane "
                           "(the springs resist only length changes; docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.area_floor_modulus_kpa, "kPa", 10, 0, 1e4,
                                    "Modulus kappa of structure.area_floor (ours)."));
  t.push_back(SYSTOLE_CHOICE(structure.body, "sphere",
                             (std::vector<std::string_view>{"sphere", "sheet", "left_heart", "lv", "mitral_leaflets"}),
                             "Scene 'mechanics': the body - a closed spherical shell, a square sheet clamped on its "
                             "edges, the LV and LA of the procedural heart anchored at the valvular plane, its LV alone, "
                             "or its two mitral leaflets anchored at the annulus (pressure = LV minus LA, closing them)."));
  t.push_back(SYSTOLE_BOOL(structure.bending, true, "Bending springs on interior edges (eq 19)."));
  t.push_back(SYSTOLE_CHOICE(structure.walls, "structure", (std::vector<std::string_view>{"structure", "chamber"}),
                             "Scene 'mechanics', bodies 'lv' and 'left_heart': 'structure' builds the walls from tissue.* "
                             "and structure.* as they read; 'chamber' builds them as scenes electromechanics, fsi and "
                             "fsei do (electromechanics.spring_law, .passive_stiffness_scale, .isotropic_passive, "
                             ".bending, and no active tension within electromechanics.passive_annulus_mm of the "
                             "anchored ring), so the coupled scenes' walls can be loaded on their own."));
  t.push_back(SYSTOLE_REAL(structure.damping_per_ms, "1/ms", 0.1, 0, 100,
                           "Mass-proportional damping gamma in m x'' = F - gamma m x' (ours; 0: none)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.time_step_safety, "", 0.9, 0, 1,
                                    "Substep = safety x 2 / omega_max (Gershgorin bound of the tangent stiffness)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.strain_limit, "", 0.6, 0, 0.99,
                                    "An edge strain |(l - l0)/l| beyond this stops the run as unstable (a guard: not "
                                    "part of a checkpoint's fingerprint, so a stopped fsi/fsei run resumes with a "
                                    "looser one)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.end_time_ms, "ms", 100, 0, 1e6, "Scene 'mechanics': simulated time."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.output_interval_ms, "ms", 5, 0, 1e5,
                                    "Scene 'mechanics': outer step (loads updated, series sampled, positions written)."));
  t.push_back(SYSTOLE_REAL(structure.cavity_pressure_mmhg, "mmHg", 5, -50, 300,
                           "Scene 'mechanics': cavity pressure (normal load p A n / 3 per node of each triangle; "
                           "on a sheet, the pressure difference across it)."));
  t.push_back(SYSTOLE_REAL(structure.pressure_ramp_ms, "ms", 20, 0, 1e5,
                           "Scene 'mechanics': pressure and active tension rise linearly over this time (updated at "
                           "least 50 times over it)."));
  t.push_back(SYSTOLE_REAL(structure.active_tension_kpa, "kPa", 0, 0, 1000,
                           "Scene 'mechanics': uniform active fibre tension (eq 24) on every node (left heart: LV and LA)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.sphere_radius_mm, "mm", 20, 0, 200, "Body 'sphere': radius."));
  t.push_back(SYSTOLE_CHOICE(structure.protocol, "ramp", (std::vector<std::string_view>{"ramp", "pv_relations"}),
                             "Scene 'mechanics': 'ramp' loads the body once (pressure and tension over "
                             "structure.pressure_ramp_ms, then held to structure.end_time_ms); 'pv_relations' (body "
                             "'lv') steps the LV through its end-diastolic (passive, 0 to structure.edpvr_max_mmhg) "
                             "and end-systolic (structure.active_tension_kpa, structure.espvr_min_mmhg to "
                             "structure.espvr_max_mmhg) pressure-volume relations, each point ramped over "
                             "structure.pressure_ramp_ms and held to rest (at most structure.end_time_ms), and "
                             "fits them (docs/structure.md)."));
  t.push_back(SYSTOLE_REAL(structure.edpvr_max_mmhg, "mmHg", 30, 0, 100,
                           "Protocol 'pv_relations': the EDPVR's highest pressure (0: no EDPVR)."));
  t.push_back(SYSTOLE_REAL(structure.espvr_min_mmhg, "mmHg", 80, 0, 300,
                           "Protocol 'pv_relations': the ESPVR's lowest pressure."));
  t.push_back(SYSTOLE_REAL(structure.espvr_max_mmhg, "mmHg", 120, 0, 300,
                           "Protocol 'pv_relations': the ESPVR's highest pressure (the ESPVR needs "
                           "structure.active_tension_kpa > 0)."));
  t.push_back(SYSTOLE_INT(structure.pv_points, "", 4, 2, 20,
                          "Protocol 'pv_relations': loaded points per relation (the EDPVR adds its unloaded point)."));
  t.push_back(SYSTOLE_INT(structure.sphere_refinement, "", 3, 0, 7,
                          "Body 'sphere': icosahedron subdivisions (10 * 4^n + 2 nodes)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.shell_thickness_mm, "mm", 2, 0, 50, "Bodies 'sphere' and 'sheet': thickness."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.sheet_size_mm, "mm", 20, 0, 500, "Body 'sheet': side of the square."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.sheet_edge_mm, "mm", 1, 0, 50, "Body 'sheet': edge length."));
  t.push_back(SYSTOLE_BOOL(structure.write_positions, true,
                           "Scene 'mechanics': node positions at every outer step to structure.h5 + .xmf."));
  t.push_back(SYSTOLE_BOOL(structure.contact, true,
                           "Contact between different bodies (solver/structure/contact.h), by structure.contact_rule."));
  t.push_back(SYSTOLE_CHOICE(structure.contact_rule, "penalty",
                             (std::vector<std::string_view>{"penalty", "cell_average"}),
                             "Contact rule: 'penalty' (node-to-surface, remembered sides; ours) or 'cell_average' (the "
                             "seed's: nodes of different bodies in one cell of side contact_distance_mm take their "
                             "mass-weighted average velocity; fails the two-sheet test, docs/structure.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(structure.contact_distance_mm, "mm", 0.5, 0, 10,
                                    "Contact layer thickness d_c: bodies are held this far apart."));
  t.push_back(SYSTOLE_REAL(structure.contact_stiffness_kpa_per_mm, "kPa/mm", 40, 0, 1e5,
                           "Contact penalty kappa: pressure kappa (d_c - gap) on a node inside the layer (enters the "
                           "stable step)."));
  t.push_back(SYSTOLE_REAL(structure.contact_damping_ratio, "", 0, 0, 2,
                           "Penalty contact, the viscous layer (ours): inside the contact layer a dashpot on the "
                           "relative velocity of a node and the surface point it touches, this fraction of the "
                           "critical damping of the pair's penalty spring (2 zeta sqrt(k mu), mu the pair's reduced "
                           "mass); its normal part never turns the push into a pull, its tangential part resists "
                           "sliding. Stills the chatter of closed valves pressed together (docs/notes/fsei-notebook.md); "
                           "shortens the contact's stable step by sqrt(1 + zeta^2) - zeta. 0: none."));
  t.push_back(SYSTOLE_BOOL(structure.mitral_limiter, true,
                           "Body 'mitral_leaflets': the seed's limiter of the leaflets' displacement towards the LA "
                           "(no chordae)."));
  t.push_back(SYSTOLE_REAL(structure.mitral_limit_mm, "mm", 1, 0, 50,
                           "Body 'mitral_leaflets': largest displacement of a leaflet node towards the LA (ours)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(
      structure.mitral_limiter_end_phase, "", 1, 0, 1,
      "Scenes 'fsi'/'fsei': the mitral limiter holds over the phases t/T in [0, this) of every beat and "
      "releases the leaflets after it (the seed limits them in systole only); 1: all the time (ours). "
      "The limiter blocks the leaflets' opening: they open by swinging about the commissures, which "
      "lifts their free edges towards the LA (docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_REAL(structure.aortic_cusp_radius_limit, "", 0, 0, 5,
                           "Bodies 'aortic_cusp_*' (scenes 'fsi'/'fsei'): a free cusp node stays within this many "
                           "aortic orifice radii of the valve's axis, or within its stress-free distance if that is "
                           "larger (ours; 0: off). 1 opens the valve to a cylinder of the orifice and keeps the "
                           "cusps off the sinus wall, where the immersed boundary left no blood between them "
                           "(docs/notes/fsei-notebook.md)."));
  // --- scene "ibm": immersed-boundary verification (nondimensional: D, U, D/U) -----------
  t.push_back(SYSTOLE_CHOICE(ibm.verification_case, "fixed_sphere",
                             (std::vector<std::string_view>{"fixed_sphere", "oscillating_sphere", "womersley_pipe",
                                                            "orifice_plate"}),
                             "Scene 'ibm': which verification flow (docs/ibm.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.reynolds, "", 20, 0, 1e5, "Scene 'ibm': Re = U D / nu."));
  t.push_back(SYSTOLE_REAL(ibm.diameter_cells, "", 8, 4, 128, "Scene 'ibm': body diameter in grid cells (D / h)."));
  t.push_back(SYSTOLE_REAL(ibm.box_diameters, "", 3, 1.5, 32,
                           "Scene 'ibm', sphere cases: box side in diameters (fixed_sphere: y and z; sets the blockage)."));
  t.push_back(SYSTOLE_REAL(ibm.box_length_diameters, "", 6, 6, 64,
                           "Scene 'ibm', fixed_sphere: streamwise box length in diameters (fringe 1.5 D, sphere at 4 D)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.end_time_convective, "D/U", 1, 0, 1e4,
                                    "Scene 'ibm': simulated time (oscillating_sphere, womersley_pipe: whole periods)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.oscillation_frequency, "U/D", 1, 0, 100,
                                    "Scene 'ibm', oscillating_sphere: cycles per D/U."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.oscillation_amplitude_diameters, "", 0.01, 0, 0.5,
                                    "Scene 'ibm', oscillating_sphere: amplitude A / D."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.womersley_number, "", 4, 0, 15,
                                    "Scene 'ibm', womersley_pipe: Wo = R sqrt(omega / nu)."));
  t.push_back(SYSTOLE_INT(ibm.forcing_iterations, "", 1, 1, 20,
                          "Scene 'ibm': direct-forcing passes per step (1 = the seed; more = multi-direct forcing)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(ibm.cfl, "", 0.2, 0, 1, "Scene 'ibm': target CFL number."));
  t.push_back(SYSTOLE_BOOL(ibm.write_fields, false,
                           "Scene 'ibm': fields (ibm_fields.h5 + .xmf) and markers (ibm_markers.csv) at the end."));
  t.push_back(SYSTOLE_REAL(ibm.marker_retraction_cells, "", 0.5, 0, 1,
                           "Scene 'ibm': markers retracted into the body by this fraction of h (Breugem 2012; 0 = the "
                           "seed; 0.5 = the diffuse MLS wall's measured offset, docs/ibm.md)."));
  t.push_back(SYSTOLE_BOOL(ibm.forcing_carry_over, false,
                           "Scene 'ibm': each step starts from the previous step's marker force (ours; stops the leak "
                           "of a thin MLS plate under a pressure jump, docs/ibm.md)."));
  t.push_back(SYSTOLE_CHOICE(ibm.valvular_plane_method, "first_node",
                             (std::vector<std::string_view>{"first_node", "mls"}),
                             "Scene 'ibm', orifice_plate: the plate by the seed's first-external-node forcing (eq 4) or "
                             "by MLS markers."));
  // --- scene "electromechanics" (solver/scene/electromechanics_scene.h) -----------------------
  t.push_back(SYSTOLE_POSITIVE_REAL(electromechanics.sync_step_ms, "ms", 1, 0, 20,
                                    "Scene 'electromechanics': synchronisation step of the multirate scheduler "
                                    "(a multiple of electro.time_step_ms; each module sub-cycles inside it)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(electromechanics.passive_stiffness_scale, "", 60, 0, 1e4,
                                    "Scene 'electromechanics': factor on the LV and LA Fung c (ours; calibrated: "
                                    "docs/electromechanics.md)."));
  t.push_back(SYSTOLE_CHOICE(electromechanics.la_chamber, "lumped",
                             (std::vector<std::string_view>{"lumped", "shell"}),
                             "Scene 'electromechanics': the LA as the 0-D elastance chamber or as a 3-D shell wall "
                             "(experimental: the constraint does not hold it yet, docs/electromechanics.md)."));
  t.push_back(SYSTOLE_REAL(electromechanics.passive_annulus_mm, "mm", 10, 0, 50,
                           "Scene 'electromechanics': wall nodes within this distance (stress-free) of the valvular "
                           "plane's anchor ring carry no active tension (ours: the fibrous annulus is not muscle); "
                           "0: none."));
  t.push_back(SYSTOLE_CHOICE(electromechanics.spring_law, "fung_tension",
                             spring_law_names(),
                             "Scene 'electromechanics': in-plane spring law of the LV and LA walls, used instead of "
                             "structure.law (calibrated: docs/electromechanics.md)."));
  t.push_back(SYSTOLE_BOOL(electromechanics.bending, false,
                           "Scene 'electromechanics': bending springs on the LV and LA walls, used instead of "
                           "structure.bending (off in the calibration: docs/electromechanics.md)."));
  t.push_back(SYSTOLE_BOOL(electromechanics.isotropic_passive, true,
                           "Scene 'electromechanics': the LV and LA cross-fibre Fung exponent set to the fibre's "
                           "(ours: a membrane without the wall's transmural fibre rotation needs cross-fibre "
                           "stiffness); false: tissue.*.alpha_c."));
  t.push_back(SYSTOLE_REAL(electromechanics.field_interval_ms, "ms", 50, 0, 1e4,
                           "Scene 'electromechanics': node positions, Vm and active tension every this over "
                           "the last beat (em_fields.h5 + .xmf); 0: none."));
  // --- scenes "fsei" and "fsi" (solver/scene/fsei_scene.h) ----------------------------------
  t.push_back(SYSTOLE_CHOICE(fsei.resolution, "coarse",
                             (std::vector<std::string_view>{"coarse", "basic", "fine", "very_fine", "custom"}),
                             "Scenes 'fsei'/'fsi': fluid grid preset in points: coarse 65x65x73, basic 129x129x145 "
                             "(the seed's grid 1), fine 193x193x257, very_fine 257x257x290 for a 140-mm box; a box "
                             "of another fluid.box_z_mm keeps the preset's spacing in z, rounded to the coarser whole "
                             "number of cells (180 mm: coarse 65x65x93, basic 129x129x186; ours); custom: "
                             "fluid.nx/ny/nz. The markers' tiling follows the grid."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fsei.sync_step_ms, "ms", 0.1, 0, 5,
                                    "Scenes 'fsei'/'fsi': synchronisation step of the multirate scheduler (fsei: a "
                                    "multiple of electro.time_step_ms); also the fluid's largest step."));
  t.push_back(SYSTOLE_REAL(fsei.end_time_ms, "ms", 0, 0, 1e6,
                           "Scenes 'fsei'/'fsi': simulated time from the start of systole; 0: beats x period."));
  t.push_back(SYSTOLE_REAL(fsei.prescribed_peak_tension_kpa, "kPa", 60, 0, 1000,
                           "Scene 'fsi': peak active tension of the prescribed LV waveform (the 0-D activation "
                           "shape, lumped timing; ours); the LA's is this times "
                           "fsei.prescribed_la_tension_fraction."));
  t.push_back(SYSTOLE_REAL(fsei.prescribed_la_tension_fraction, "-", 1, 0, 2,
                           "Scene 'fsi': the LA's peak prescribed tension over the LV's (ours; 1: the same "
                           "peak; at 120 kPa the LA's contraction peaks at 46 mmHg, "
                           "docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fsei.probe_radius_mm, "mm", 4, 0, 20,
                                    "Scenes 'fsei'/'fsi': radius of the pressure probe spheres in the LV, LA, aortic "
                                    "root and outer fluid (chamber pressures are their mean pressures, relative to the "
                                    "outer probe; ours)."));
  t.push_back(SYSTOLE_BOOL(fsei.strong_coupling, false,
                           "Scenes 'fsei'/'fsi': strong coupling (fluid and structure repeated per interval, "
                           "coupling.strong_tolerance and strong_max_iterations) instead of the seed's loose "
                           "coupling."));
  // fsei.forcing: the immersed boundary's direct forcing (solver/ibm/forcing.h)
  t.push_back(SYSTOLE_CHOICE(fsei.forcing.kernel, "mls", (std::vector<std::string_view>{"mls", "divergence_free"}),
                             "Scenes 'fsei'/'fsi': the immersed boundary's interpolation and spreading weights: mls "
                             "(the seed's moving least squares) or divergence_free (ours: composite B-splines, "
                             "quadratic along a velocity component's own direction and linear across, after "
                             "Gruninger & Griffith 2025; the interpolated velocity has no flux through a closed "
                             "wall, so the walls stop leaking their volume: FsiSphere.TheDivergenceFreeKernelHoldsTheVolumeTheMlsKernelLoses)."));
  t.push_back(SYSTOLE_INT(fsei.forcing.iterations, "", 3, 1, 20,
                          "Scenes 'fsei'/'fsi': direct-forcing passes per fluid step (multi-direct forcing; 3 "
                          "cut the leak through the heart's walls 7x against the seed's single pass: "
                          "docs/fsei.md)."));
  t.push_back(SYSTOLE_BOOL(fsei.forcing.carry_over, false,
                           "Scenes 'fsei'/'fsi': carry the immersed-boundary force over between fluid steps "
                           "(ours; it made the membrane sphere tight but set off an oscillation in the heart "
                           "within 10 ms: docs/fsei.md)."));
  t.push_back(SYSTOLE_REAL(fsei.forcing.carry_over_exclusion_cells, "", 0, 0, 4,
                           "Scenes 'fsei'/'fsi', with fsei.forcing.carry_over: markers within this many grid "
                           "spacings of another body's markers carry no force over (ours; anti-windup where two "
                           "bodies' targets conflict in one support, e.g. leaflets meeting at a commissure); 0: "
                           "every marker carries. docs/fsei.md."));
  t.push_back(SYSTOLE_BOOL(fsei.forcing.carry_over_exclusion_plane, true,
                           "Scenes 'fsei'/'fsi', with the carry-over's exclusion: true, the rigid valvular plane's "
                           "markers next to another body carry nothing over, as every body's; false, they keep "
                           "their carry-over (ours: the plane is the largest leak left; with MLS a cusp crumpled "
                           "next to it: docs/notes/fsei-notebook.md). The other bodies' markers next to the "
                           "plane carry none either way."));
  t.push_back(SYSTOLE_REAL(fsei.forcing.carry_over_exclusion_plane_cells, "", 0, 0, 4,
                           "Scenes 'fsei'/'fsi', with fsei.forcing.carry_over: markers within max(this, "
                           "fsei.forcing.carry_over_exclusion_cells) grid spacings of the rigid valvular plane's "
                           "markers carry no force over (ours; a wider anti-windup ring where the chambers' walls "
                           "meet the plane); 0: the plane as any body (docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_REAL(fsei.forcing.carry_over_exclusion_plane_wall_cells, "", 0, 0, 4,
                           "Scenes 'fsei'/'fsi', with fsei.forcing.carry_over: the walls' markers (LV, LA, aorta) "
                           "within max(this, fsei.forcing.carry_over_exclusion_plane_cells, "
                           "fsei.forcing.carry_over_exclusion_cells) grid spacings of the rigid valvular plane's "
                           "markers carry no force over (ours); the leaflets and cusps keep the narrower ring, so "
                           "the closed valves' bases keep their hold; 0: the walls as any body: at 1 h a stiff LA wound up below the "
                           "plane at 180 bpm; with the ring on every body the closed aortic valve passed 1.22 ml back over the "
                           "diastole against 0.39 ml on the walls only (docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_REAL(fsei.forcing.carry_over_reference_cfl, "", 0, 0, 1,
                           "Scenes 'fsei'/'fsi', with fsei.forcing.carry_over: 0 (off), or the CFL target whose "
                           "step sets the carry-over's rate (ours): each fluid step the carried force keeps the share "
                           "min(1, the fluid's stable step at fluid.cfl / its stable step at this CFL) of the step's "
                           "forcing corrections (the force applied in the step is unchanged), so the carried force's error falls at the "
                           "reference step's rate per unit of time whatever fluid.cfl (1 where max_dt or the "
                           "viscous bound sets both steps). At the seed's CFL 0.2 with 0.4 the stress points that ran away "
                           "complete (CarryOverIncrementShare.*, docs/notes/fsei-notebook.md)."));
  // fsei.aorta: the aorta's ground pressure and how it is held
  t.push_back(SYSTOLE_REAL(fsei.aorta.ground_pressure_mmhg, "mmHg", 60, 0, 150,
                           "Scenes 'fsei'/'fsi': the aorta's ground pressure (the seed's 60 mmHg pre-tension), "
                           "held as fsei.aorta.pretension says: an outer pressure on the aorta's wall outside the "
                           "Darcy region (ours: a follower load, held) with the blood inside the aorta started at "
                           "it, so the built aorta is in equilibrium; or partly by the wall's pre-stress "
                           "(fsei.aorta.prestress_fraction) and the outer load the rest (docs/fsei.md)."));
  t.push_back(SYSTOLE_REAL(fsei.aorta.pressure_ramp_ms, "ms", 0, 0, 200,
                           "Scenes 'fsei'/'fsi': 0: the aorta's ground pressure is there at t = 0 (blood inside "
                           "started at it); else the outer load on the aorta's wall rises linearly over this time "
                           "from the blood at rest (ours: the closed cusps are loaded gradually; docs/fsei.md)."));
  t.push_back(SYSTOLE_CHOICE(fsei.aorta.pretension, "outer_load",
                             (std::vector<std::string_view>{"outer_load", "prestress"}),
                             "Scenes 'fsei'/'fsi': how the aorta's wall holds fsei.aorta.ground_pressure_mmhg (ours; the "
                             "seed: 'pretensioned by an external force'): outer_load, an outer pressure as large on "
                             "the wall (the wall stays untensioned); prestress, the wall's springs shortened so that "
                             "the built aorta is in equilibrium with that pressure inside and none outside "
                             "(solver/structure/prestress.h; with fsei.aorta.pressure_ramp_ms the shortening is "
                             "ramped). docs/fsei.md."));
  t.push_back(SYSTOLE_REAL(fsei.aorta.prestress_fraction, "", 1, 0.05, 1,
                           "Scenes 'fsei'/'fsi', with fsei.aorta.pretension = prestress: the share of "
                           "fsei.aorta.ground_pressure_mmhg the aorta's wall carries by its pre-stress; the rest, (1 - share) "
                           "x the ground pressure, by the outer load (ours: a wall pre-stressed for all of it sits on "
                           "the stiff part of the Fung law, 0.46 ml/mmHg dry at 60-70 mmHg against 1.05 with the "
                           "outer load alone, which buckles when the blood's pressure falls below it; "
                           "bench/structure/aorta_compliance, docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_BOOL(fsei.aorta.outlet_held, true,
                           "Scenes 'fsei'/'fsi': hold the aorta's Darcy outlet (its last 1.5 diameters) in place "
                           "(ours: the seed anchors every body to the valvular plane only; held, the descending "
                           "aorta cannot swing into the box's wall, and the thoracic aorta is tethered to the spine)."));
  t.push_back(SYSTOLE_CHOICE(fsei.slab_split, "balanced", (std::vector<std::string_view>{"balanced", "uniform"}),
                             "Scenes 'fsei'/'fsi' on several MPI ranks: how the fluid's z planes are split over the "
                             "ranks: balanced (ours), by each plane's work, its cells plus the immersed boundary's "
                             "share in proportion to the bodies' surface in it (docs/benchmarks.md: with equal "
                             "blocks one of 2 ranks waited half its time); uniform, equal blocks. Results agree to "
                             "round-off; not part of a checkpoint's fingerprint."));
  t.push_back(SYSTOLE_CHOICE(fsei.sync_interval, "fixed", (std::vector<std::string_view>{"fixed", "fluid_step"}),
                             "Scenes 'fsei'/'fsi': the synchronisation intervals: fixed, fsei.sync_step_ms each; "
                             "fluid_step (ours), each the fluid's stable (CFL) step at its start, at most "
                             "fsei.sync_step_ms, so the fluid takes one step per interval and coupling pass instead "
                             "of filling a fixed interval with one or two (docs/benchmarks.md: with strong coupling "
                             "the passes repeat the fluid's steps)."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fsei.abort_mean_speed_m_s, "m/s", 1, 0, 20,
                                    "Scenes 'fsei'/'fsi': the guard for a runaway (ours): at every sample the "
                                    "fluid box's kinetic energy E is spread over the blood of the LV and the LA (their "
                                    "volumes V) as a mean speed sqrt(2E / (rho V)); above this speed and above "
                                    "fsei.abort_mean_speed_orifice_ratio x the largest mean velocity through a valve's "
                                    "orifice so far (flow / orifice area) the run stops with the fastest cell, the "
                                    "time and how long the energy took to double. Energy let in by the coupling over "
                                    "tens of ms trips it where the fluid's per-step guards do not ("
                                    "docs/notes/fsei-notebook.md), and so does a blow-up within a few ms. A guard, not a parameter of "
                                    "the trajectory: a checkpoint resumes with another value."));
  t.push_back(SYSTOLE_POSITIVE_REAL(fsei.abort_mean_speed_orifice_ratio, "", 1, 0, 100,
                                    "Scenes 'fsei'/'fsi': the slow-runaway guard's second bound (ours; see "
                                    "fsei.abort_mean_speed_m_s): the chambers' mean speed over the largest mean velocity "
                                    "through a valve's orifice so far. Runs through the ejection at 70 and 180 bpm stayed "
                                    "at 0.69-0.80 of it to 0.4 T, runaways crossed 1 (docs/notes/fsei-notebook.md); a "
                                    "whole 180-bpm beat at the defaults crosses it at 0.48 T, its energy rising while "
                                    "the flow falls, a real runaway (relaxed to 3 it gained energy to 655 mJ by 189 ms)."));
  t.push_back(SYSTOLE_INT(fsei.fluid_steps_per_interval, "", 1, 1, 8,
                          "Scenes 'fsei'/'fsi' with fsei.sync_interval = fluid_step: each interval is this many "
                          "of the fluid's stable steps at its start (still at most fsei.sync_step_ms; ours): fewer "
                          "intervals, so fewer coupling passes and fewer structure and load evaluations, against "
                          "a larger change per interval. With fixed intervals it must stay 1."));
  t.push_back(SYSTOLE_CHOICE(fsei.coupling_order, "fluid_first", (std::vector<std::string_view>{"fluid_first", "structure_first"}),
                             "Scenes 'fsei'/'fsi': the order of a coupling pass: fluid_first (the seed's: EP, the "
                             "fluid, then the shells with its loads) or structure_first (ours: EP, the shells with "
                             "the loads last written, then the fluid at their new shape; strong coupling only). "
                             "structure_first measures an interval's first pass too (the loads it makes against "
                             "those the shells used), so an interval whose loads change less than "
                             "coupling.strong_tolerance ends after one pass instead of two. Alone (with the lagging "
                             "'last' guess) such one-pass intervals let an oscillation of the LV wall and its blood "
                             "grow in the ejection (docs/notes/fsei-notebook.md); with the 'linear' first-pass guess it "
                             "is part of the fsi/fsei calibrated defaults."));
  t.push_back(SYSTOLE_CHOICE(fsei.first_pass_predictor, "last", (std::vector<std::string_view>{"last", "linear"}),
                             "Scenes 'fsei'/'fsi' with fsei.coupling_order = structure_first: the loads the shells "
                             "take in an interval's first pass: last (those last written: they lag one interval) "
                             "or linear (ours: extrapolated from the last two intervals' loads, a second-order "
                             "guess; the first pass's residual then measures the guess); linear is part of the "
                             "fsi/fsei calibrated defaults (docs/notes/fsei-notebook.md)."));
  t.push_back(SYSTOLE_REAL(fsei.field_interval_ms, "ms", 0, 0, 1e5,
                           "Scenes 'fsei'/'fsi': 0: no fields; else a frame every this from t = 0, and one of the "
                           "bodies when a run stops unstable: the fluid's velocity (m/s), pressure (mmHg) and "
                           "vorticity (1/s) in fsei_fluid_<k>.h5, every body's nodes (positions, velocities, the "
                           "largest edge strain, the wall shear stress; the LV's and LA's active tension and, in "
                           "scene fsei, transmembrane potential) in fsei_bodies.h5, and fsei_fields.xmf that "
                           "shows them together in ParaView (mm), in the output directory."));
  t.push_back(SYSTOLE_REAL(fsei.checkpoint_interval_ms, "ms", 10, 0, 1e5,
                           "Scenes 'fsei'/'fsi': the whole coupled state is checkpointed every this much simulated "
                           "time where the caller keeps checkpoints (a worker: per job, so a requeued job resumes; "
                           "systole-solve --checkpoint-dir); a run finding a checkpoint of the same scenario there "
                           "resumes from it, bitwise as the straight run (docs/fsei.md). 0: none."));
  t.push_back(SYSTOLE_CHOICE(fsei.defaults, "calibrated", (std::vector<std::string_view>{"calibrated", "seed"}),
                             "Scenes 'fsei'/'fsi': the defaults of the fields a scenario leaves out. calibrated "
                             "(ours): the setting of the beats recorded in docs/fsei.md, shown in parentheses in "
                             "this table's default column (the divergence-free kernel with the carry-over forcing, "
                             "strong IQN-ILS coupling at the fluid's step with the shells first, the carry-over's "
                             "rate held at CFL 0.4's step, the aorta "
                             "pre-stressed for a quarter of its ground pressure, the tissue at 3 g/ml, 120 kPa of "
                             "prescribed tension with the LA at 0.4 of it, a 180-mm box). seed: every field's own "
                             "default, the seed's values where the seed gives one; with them the closed aortic valve "
                             "crumples within 35 ms (docs/notes/fsei-notebook.md). A field the scenario sets is "
                             "never replaced."));
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

const std::vector<SceneDefault>& fsei_calibrated_defaults() {
  // Run la4's setting and what later runs added (docs/notes/fsei-notebook.md), field by field; every value is in its
  // field's range (tests/unit/config_test.cc parses the layer).
  static const std::vector<SceneDefault> layer{
      // the immersed boundary: closed walls that hold their forcing
      {"fsei.forcing.kernel", "divergence_free"},
      {"fsei.forcing.carry_over", "true"},
      // within 1 h of another body no carry-over (2 h switched it off along the closed cusps' coaptation
      // strips, which then passed 18 ml/s back into the LV through the diastole)
      {"fsei.forcing.carry_over_exclusion_cells", "1"},
      {"fsei.forcing.carry_over_exclusion_plane", "false"},
      // the walls' (LV, LA, aorta) markers within 2 h of the valvular plane carry none over
      // (at 1 h a stiff LA wound up below the plane at 180 bpm; with the ring on the walls only the
      // closed aortic cusps keep their seal: 0.39 ml back over the diastole, 1.22 with it on every body)
      {"fsei.forcing.carry_over_exclusion_plane_wall_cells", "2"},
      // the fluid's step: CFL 0.4 (every whole fsi beat recorded ran at 0.4,
      // which moved EF by 0.5 % against 0.2 for 41 % less time; at the seed's 0.2 the heart at these
      // defaults ran away late in the ejection at 70 bpm, stopped by the slow-runaway guard at 229 ms)
      {"fluid.cfl", "0.4"},
      // the carry-over's rate per unit of time held at CFL 0.4's at any smaller step (at the
      // seed's CFL 0.2 the two stress points that had stopped, 70 bpm x1 and 180 bpm x0.5, complete;
      // at CFL 0.4 and above the share is 1, the runs bitwise those without it)
      {"fsei.forcing.carry_over_reference_cfl", "0.4"},
      // the coupling: strong, IQN-ILS, one fluid step per interval, the shells first
      {"fsei.strong_coupling", "true"},
      {"coupling.relaxation", "iqn_ils"},
      {"coupling.strong_tolerance", "0.01"},
      {"coupling.strong_max_iterations", "12"},
      {"fsei.sync_interval", "fluid_step"},
      {"fsei.coupling_order", "structure_first"},
      {"fsei.first_pass_predictor", "linear"},
      // the aorta and its afterload
      {"fsei.aorta.pretension", "prestress"},
      {"fsei.aorta.pressure_ramp_ms", "20"},
      {"fsei.aorta.prestress_fraction", "0.25"},
      {"tissue.aorta.fung_c_pa", "4312"},
      {"fluid.darcy_permeability", "0.016"},
      {"fluid.box_z_mm", "180"},
      // the tissue and the valves
      {"tissue.density_g_per_ml", "3"},
      {"geometry.valve_gap_mm", "1"},
      {"electromechanics.bending", "true"},
      {"structure.area_floor", "0.5"},
      {"structure.strain_limit", "0.75"},
      {"structure.aortic_cusp_radius_limit", "1.15"},
      // the prescribed activation of scene fsi
      {"fsei.prescribed_peak_tension_kpa", "120"},
      {"fsei.prescribed_la_tension_fraction", "0.4"},
      // the EP-driven tension of scene fsei in blood: the electromechanics scene's
      // 340 kPa, calibrated against its 0-D afterload, drove the LV to 170 mmHg by 0.16 T
      {"tissue.active_tension_k_kpa", "250", "fsei"},
  };
  return layer;
}

const SceneDefault* find_fsei_calibrated_default(std::string_view path) {
  for (const SceneDefault& d : fsei_calibrated_defaults())
    if (d.path == path) return &d;
  return nullptr;
}

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
    case Kind::kString:
      out << "any text";
      break;
  }
  return out.str();
}

std::string parameters_markdown() {
  std::ostringstream out;
  out << "# Scenario parameters\n\n"
      << "Generated by `systole-solve --list-parameters` from solver/config/parameter_table.cc; "
         "do not edit by hand.\nDefaults are the seed's healthy left heart at 70 bpm "
         "(../shared/MODEL.md); scenes fsi and fsei take the value in parentheses instead unless the "
         "scenario sets the field or `fsei.defaults = seed` (the calibrated setting of docs/fsei.md).\n\n"
      << "| field | unit | default | allowed | meaning |\n|---|---|---|---|---|\n";
  for (const Param& p : parameter_table()) {
    std::string def;
    switch (p.kind) {
      case Kind::kReal:
      case Kind::kInt: def = format_number(p.default_number); break;
      case Kind::kBool: def = p.default_number != 0 ? "true" : "false"; break;
      case Kind::kChoice: def = std::string(p.default_choice); break;
      case Kind::kString: def = p.default_choice.empty() ? "\"\"" : std::string(p.default_choice); break;
      case Kind::kRealList:
      case Kind::kChoiceList: def = "[]"; break;
    }
    if (const SceneDefault* d = find_fsei_calibrated_default(p.path))
      def += " (" + (d->scene.empty() ? std::string("fsi/fsei") : std::string(d->scene)) + ": " + std::string(d->value) + ")";
    out << "| `" << p.path << "` | " << (p.unit.empty() ? "-" : std::string(p.unit)) << " | " << def
        << " | " << describe_allowed(p) << " | " << p.doc << " |\n";
  }
  out << "\n" << removed_fields_markdown();
  return out.str();
}

}  // namespace systole::config
