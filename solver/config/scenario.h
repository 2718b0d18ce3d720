#pragma once
// Typed, validated scenario: what every scene reads. Built only by parse_scenario() (or
// default_scenario()), so a Scenario object is always complete and within range.
//
// Field names mirror proto/systole/v1/scenario.proto (same paths, same units in the names).
// Defaults, units, ranges and docs are NOT written here: they live once, in the parameter
// table (parameter_table.cc). No member initialisers on purpose.
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace systole::config {

struct FungTissue {
  double fung_c_pa;
  double alpha_f;
  double alpha_c;
};

struct Tissue {
  FungTissue lv, la, mitral_leaflets, aortic_leaflets, aorta;
  double density_g_per_ml;
  double poisson_ratio;
  double active_tension_k_kpa;
  double active_tension_time_scale_ms;  // Nash-Panfilov t_scale (eq 23)
  double active_min_fibre_stretch;      // length-tension (ours); 0: none
  double active_cross_fibre_fraction;   // cross-fibre active stress / fibre (ours); 0: none
};

struct Geometry {
  double lv_short_axis_mm, lv_long_axis_mm, lv_wall_mm, lv_volume_ml;
  double la_volume_ml, la_wall_mm;
  double mitral_diameter_mm, aortic_diameter_mm;
  double mitral_leaflet_length_mm, mitral_leaflet_thickness_mm, aortic_leaflet_thickness_mm;
  double aortic_root_diameter_mm, aortic_arch_diameter_mm, aortic_descending_diameter_mm;
  double aorta_wall_mm;
  double pulmonary_vein_diameter_mm;
  double lv_fibre_angle_deg;
  double target_edge_mm;
  double marker_spacing_fraction;
  double valve_gap_mm;  // between the free edges of neighbouring closed leaflets / cusps (ours)
  double aortic_commissure_height_per_radius;  // crown-shaped cusp attachment; 0: flat annulus (ours)
  double darcy_region_length_per_diameter;     // the Darcy outflow region's length / descending diameter (ours)
  double mitral_rest_opening_mm;  // the mitral leaflets' stress-free shape opened this far; 0: closed (ours)
};

struct Stimulus {
  double duration_ms;
  double amplitude_ua_per_cm2;
  double box_size_mm;
};

struct Electro {
  std::string model;
  double surface_to_volume_per_cm;
  double membrane_capacitance_uf_per_cm2;
  double sigma_e_fibre_ms_per_cm, sigma_e_cross_ms_per_cm;
  double sigma_i_fibre_ms_per_cm, sigma_i_cross_ms_per_cm;
  std::string lv_cell_model, la_cell_model;
  Stimulus stimulus;
  double time_step_ms;
  std::string splitting;
  std::string mesh;
  double mesh_size_x_mm, mesh_size_y_mm, mesh_size_z_mm;
  double mesh_spacing_mm;
  double fibre_angle_deg;
  double end_time_ms;
  double activation_threshold_mv;
  bool purkinje;                                // Purkinje surrogate on the LV (ours)
  double purkinje_conduction_velocity_m_per_s;  // delay of each site = distance / this
  int purkinje_sites;                           // early-activation sites spread over the LV
  double la_conductivity_scale;                 // factor on sigma_i, sigma_e in the LA (ours)
  int threads;                                  // OpenMP threads of the reaction step
  std::string mesh_manifest;                    // mesh = "manifest": server-side manifest path
};

struct Fluid {
  double kinematic_viscosity_m2_per_s;
  std::string viscosity_model;
  int nx, ny, nz;
  double box_x_mm, box_y_mm, box_z_mm;
  double cfl;
  std::string cfl_rule;  // scenes fsi/fsei: fluid::FluidParameters::cfl_rule
  std::string subgrid_model;  // fluid::FluidParameters::subgrid_model ("none" | "vreman", ours)
  double subgrid_constant;    // fluid::FluidParameters::subgrid_constant (Vreman's c)
  double max_dt_ms;
  double darcy_permeability;
  double carreau_yasuda_mu0_pa_s, carreau_yasuda_mu_inf_pa_s, carreau_yasuda_lambda_s;
  double carreau_yasuda_n, carreau_yasuda_a;
  double density_kg_per_m3;
  std::string verification_case;
  double end_time_ms;
  double womersley_number;
  bool write_fields;
};

struct Chamber {
  double emax_mmhg_per_ml;
  double emin_mmhg_per_ml;
  double v0_ml;
  double contraction_ms;
  double relaxation_ms;
};

struct Lumped {
  Chamber lv, la;
  double mitral_resistance_mmhg_s_per_ml;
  double aortic_resistance_mmhg_s_per_ml;
  double mitral_inertance_mmhg_s2_per_ml;
  double aortic_inertance_mmhg_s2_per_ml;
  double valve_backflow_conductance_fraction;
  double aortic_characteristic_impedance_mmhg_s_per_ml;
  double systemic_resistance_mmhg_s_per_ml;
  double systemic_compliance_ml_per_mmhg;
  double pulmonary_venous_compliance_ml_per_mmhg;
  double pulmonary_venous_resistance_mmhg_s_per_ml;
  double stressed_blood_volume_ml;
  double time_step_ms;
};

struct Coupling {
  std::string mode;
  double strong_tolerance;
  int strong_max_iterations;
  std::string relaxation;
  int iqn_reuse_intervals;
};

struct Outputs {
  bool metrics;
  bool time_series;
  double time_series_interval_ms;
  int time_series_last_beats;
  std::vector<std::string> fields;
  std::vector<double> field_phases;
};

struct Analytic {
  std::string function;
  double x1, x2, x3;
  double a, b;
};

// Scene "mechanics" and the structure module (solver/structure/README.md).
struct Structure {
  std::string law;
  std::string membrane;                 // "springs" | "triangles": ShellOptions::membrane (ours)
  std::string body;
  std::string walls;                    // "structure" | "chamber": bodies lv, left_heart as the coupled scenes build them
  std::string protocol;                 // scene mechanics: "ramp" | "pv_relations"
  double edpvr_max_mmhg;                // protocol pv_relations: EDPVR from 0 to this (0: none)
  double espvr_min_mmhg, espvr_max_mmhg;  // protocol pv_relations: the ESPVR's pressures
  int pv_points;                        // protocol pv_relations: loaded points per relation
  bool bending;
  double damping_per_ms;
  double time_step_safety;
  double strain_limit;
  double end_time_ms;
  double output_interval_ms;
  double cavity_pressure_mmhg;
  double pressure_ramp_ms;
  double active_tension_kpa;
  double sphere_radius_mm;
  int sphere_refinement;
  double shell_thickness_mm;
  double sheet_size_mm;
  double sheet_edge_mm;
  bool write_positions;
  bool contact;                         // between different bodies (solver/structure/contact.h)
  std::string contact_rule;             // "penalty" | "cell_average" (the seed's)
  double contact_distance_mm;
  double contact_stiffness_kpa_per_mm;
  double contact_damping_ratio;         // penalty contact: the viscous layer / its critical damping (ours; 0: none)
  bool mitral_limiter;                  // body "mitral_leaflets": the seed's displacement limiter
  double mitral_limit_mm;
  double mitral_limiter_end_phase;      // scenes fsi/fsei: the limiter holds over phases [0, this) (1: always, ours)
  double aortic_cusp_radius_limit;      // bodies "aortic_cusp_*": radial limiter / orifice radius (ours; 0: off)
  double fung_exponent_cap;             // law "fung_tension": largest a eps^2 (ours)
  double fung_compression_fraction;     // law "fung_tension": Fung stiffening kept in compression (ours)
  double area_floor;                    // ShellOptions::area_floor (ours; 0: off)
  double area_floor_modulus_kpa;        // ShellOptions::area_floor_modulus_kpa (ours)
};

// Scene "ibm": immersed-boundary verification flows (solver/scene/ibm_scene.h), nondimensional
// (D, U, D/U).
struct Ibm {
  std::string verification_case;
  double reynolds;
  double diameter_cells;
  double box_diameters;
  double box_length_diameters;
  double end_time_convective;
  double oscillation_frequency;
  double oscillation_amplitude_diameters;
  double womersley_number;
  int forcing_iterations;
  double cfl;
  bool write_fields;
  double marker_retraction_cells;
  bool forcing_carry_over;
  std::string valvular_plane_method;
};

// Scene "electromechanics" (solver/scene/electromechanics_scene.h).
struct Electromechanics {
  double sync_step_ms;             // scheduler synchronisation step, a multiple of the EP step
  double passive_stiffness_scale;  // factor on the LV and LA Fung c in this scene (ours)
  std::string la_chamber;          // "shell" or "lumped"
  double field_interval_ms;        // node fields over the last beat; 0: none
  double passive_annulus_mm;       // no active tension within this distance of the anchor ring (ours)
  std::string spring_law;          // the chamber walls' law in this scene (instead of structure.law)
  bool bending;                    // bending on the chamber walls (instead of structure.bending)
  bool isotropic_passive;          // alpha_c = alpha_f for the LV and LA in this scene (ours)
};

// Scenes "fsei" and "fsi" (solver/scene/fsei_scene.h).
struct Fsei {
  // The immersed boundary's direct forcing (ibm::ForcingParameters; MODEL.md eq 3, 8).
  struct Forcing {
    std::string kernel;                     // "mls" | "divergence_free": ibm::ForcingParameters::kernel (ours)
    int iterations;                         // ibm::ForcingParameters::iterations
    bool carry_over;                        // ibm::ForcingParameters::carry_over (ours)
    double carry_over_exclusion_cells;      // ibm::ForcingParameters::carry_over_exclusion_cells (ours)
    bool carry_over_exclusion_plane;        // ibm::ForcingParameters::carry_over_exclusion_rigid (ours)
    double carry_over_exclusion_plane_cells;  // ibm::ForcingParameters::carry_over_exclusion_rigid_cells (ours)
    double carry_over_exclusion_plane_wall_cells;  // ibm::ForcingParameters::carry_over_exclusion_rigid_wall_cells (ours)
    double carry_over_reference_cfl;        // coupling::FluidModuleOptions::carry_over_reference_cfl, 0: off (ours)
  };
  // The aorta and how it holds its ground pressure (the seed's pre-tension).
  struct Aorta {
    double ground_pressure_mmhg;            // the ground pressure at t = 0 (an outer load on its wall)
    double pressure_ramp_ms;                // 0: at once; else the outer load ramped over it, blood from rest (ours)
    std::string pretension;                 // "outer_load" | "prestress": how the wall holds the ground pressure (ours)
    double prestress_fraction;              // with "prestress": the wall's share of the ground pressure, the rest an outer load (ours)
    bool outlet_held;                       // the Darcy outlet (kOutflow nodes) held (ours)
  };
  std::string resolution;               // grid preset: coarse, basic, fine, very_fine, custom
  double sync_step_ms;                  // scheduler synchronisation step
  double end_time_ms;                   // 0: beats x period
  double prescribed_peak_tension_kpa;   // fsi: peak of the activation waveform, the LV's (ours)
  double prescribed_la_tension_fraction;  // fsi: the LA's peak over the LV's (ours)
  double probe_radius_mm;               // pressure probe spheres
  bool strong_coupling;                 // false: loose (the seed's)
  Forcing forcing;
  Aorta aorta;
  double field_interval_ms;             // 0: no fields; else a frame of fluid and bodies every this
  double checkpoint_interval_ms;        // the whole coupled state every this (RunControl::checkpoint_directory)
  std::string slab_split;               // "balanced" | "uniform": grid::Slabs' z split over the ranks (ours)
  std::string sync_interval;            // "fixed" | "fluid_step": coupling::SchedulerOptions::interval_stage (ours)
  int fluid_steps_per_interval;         // with "fluid_step": coupling::SchedulerOptions::interval_stage_steps (ours)
  std::string coupling_order;           // "fluid_first" | "structure_first": the stages' order; structure_first
                                        // measures strong coupling's first pass (SchedulerOptions::first_pass_residual) (ours)
  std::string first_pass_predictor;     // "last" | "linear": SchedulerOptions::first_pass_predictor (ours)
  std::string defaults;                 // "calibrated" | "seed": which defaults fsi/fsei take (parse_scenario; ours)
  double abort_mean_speed_m_s;          // the slow-runaway guard: the box's kinetic energy over the LV's and LA's
  double abort_mean_speed_orifice_ratio;  // blood as a mean speed above both this and the ratio x the largest mean
                                          // velocity through an orifice so far stops the run (ours)
};

struct Scenario {
  std::string scene;
  double heart_rate_bpm;
  int beats;
  double av_delay_ms;
  double periodicity_tolerance;
  Tissue tissue;
  Geometry geometry;
  Electro electro;
  Fluid fluid;
  Lumped lumped;
  Coupling coupling;
  Outputs outputs;
  Analytic analytic;
  Structure structure;
  Ibm ibm;
  Electromechanics electromechanics;
  Fsei fsei;

  double period_ms() const { return 60000.0 / heart_rate_bpm; }
};

// Scene "mechanics": structure.walls = "chamber" needs body "lv" or "left_heart";
// structure.protocol = "pv_relations" needs body "lv", an ESPVR range that rises, and something
// to measure. Appends one message per problem (parse_scenario runs it; so does the scene registry).
void check_mechanics_rules(const Scenario& scenario, std::vector<std::string>& errors);

// Every default from the parameter table: the seed's healthy left heart at 70 bpm.
Scenario default_scenario();

// Parses a scenario from JSON with snake_case field names (proto field names). Missing fields
// take their defaults; unknown fields, wrong types, out-of-range values and inconsistent
// combinations are all collected and thrown together as one systole::InputError whose
// message has one line per problem, each naming the field, the value and what is allowed.
Scenario parse_scenario(const nlohmann::json& document);

// Every problem parse_scenario() would throw, one message per problem; empty for a valid
// document. For callers that report a scenario's problems together with their own.
std::vector<std::string> scenario_problems(const nlohmann::json& document);

// The complete scenario (every field, defaults expanded) as JSON: provenance and caching key.
nlohmann::json to_json(const Scenario& scenario);

// Applies one `path.to.field=value` override to a JSON document (before parse_scenario).
// The path must name a field of the parameter table; the value is converted to the field's
// type (numbers, true/false, strings, comma-separated lists). Throws InputError otherwise.
void apply_override(nlohmann::json& document, const std::string& assignment);

// Scenes known to the project and the ones this build can run. A known but unimplemented
// scene is rejected with a message listing the implemented ones (never a silent fallback).
const std::vector<std::string>& known_scenes();
const std::vector<std::string>& implemented_scenes();

}  // namespace systole::config
