#pragma once
// ShellModel: one thin-shell body as a spring network (MODEL.md §5, eq 15-20, 24-25) with its
// explicit, sub-cycling integrator.
//
// Units (internal and at the interface): mm, mg, ms. Derived: force mN, stress and pressure
// kPa (= mN/mm^2), energy uJ (= mN mm), density mg/mm^3 (1.05 g/ml = 1.05 mg/mm^3).
//
// Forces on node positions x (all conservative, so every one is minus the gradient of the
// energy reported by energies()):
//   - in-plane springs, one per edge (eq 17-18): f = tau(eps) C / l along the edge, eps =
//     (l - l0)/l, C = sum_T s_T A_T over the edge's triangles in the stress-free mesh (ours:
//     eq 18's s (A1 + A2) with the areas frozen, which makes the spring hyperelastic);
//     tau from the law registry (spring_law.h) with c of the tissue and alpha_phi from the
//     edge's angle to the fibre of its triangles (ours: mean of cos^2 phi over them);
//   - bending, one per interior edge (eq 19): W = k_b [1 - cos(theta - theta0)], theta the
//     signed angle between the two face normals, theta0 from the stress-free mesh,
//     k_b = 2B/sqrt(3), B = c alpha_phi s^3 / [12 (1 - nu^2)];
//   - active fibre tension (eq 24, (ours) form): a per-node tension tau_act (kPa), averaged
//     on each triangle, acts as a contractile stress along the triangle's fibre:
//     W_act = sum_T tau_act s_T A_T lambda_f, lambda_f = |F f0| the fibre stretch. Its nodal
//     forces have eq 24's magnitude (tau s l) but sum to zero with zero torque, unlike the
//     literal eq 24 (a force along e_f at every node, which pushes a whole body); optionally
//     scaled by a length-tension factor f(lambda_f) (ShellOptions::active_min_fibre_stretch, ours),
//     and with a cross-fibre fraction k: + k tau s A g(lambda_c) (active_cross_fibre_fraction, ours);
//   - an in-plane area floor (ours, options.area_floor J0 > 0; off in the seed): on every triangle
//     whose area ratio J = A/A0 is below J0, W = kappa s A0 (J0 - J)^2 / J, kappa =
//     options.area_floor_modulus_kpa; its force kappa s (J0^2/J^2 - 1) dA/dx pushes the area up
//     and grows without bound as J -> 0, so a triangle cannot be squeezed flat in its plane (the
//     springs resist only length changes); W and its slope vanish at J0 (reported in elastic_uj);
//   - cavity pressure p (kPa, follower load): -p A_T n_T / 3 on each node of triangle T
//     (normals into the cavity, so p > 0 inflates), = p dV/dx for a closed surface;
//   - external nodal loads (mN) from the caller, held constant during advance().
// Newton per node (eq 25): m x'' = F - gamma m x' (optional mass-proportional damping, ours).
// Node masses (eq 15): m_i = (1/3) sum_T rho s_T A_T.
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/tri_mesh.h"
#include "solver/structure/spring_law.h"

namespace systole::structure {

using Vec3 = geometry::Vec3;

struct TissueMaterial {
  double c_kpa;  // Fung c
  double alpha_f, alpha_c;
};

struct ShellMaterials {
  std::array<TissueMaterial, geometry::kTissueCount> tissue;  // indexed by geometry::Tissue
  double density_mg_per_mm3;
  double poisson_ratio;  // nu_m of the bending modulus
};

// The scenario's tissue section (Pa -> kPa, g/ml -> mg/mm^3). The rigid valvular plane and the
// vein-ostium caps get the LV's and LA's properties (they are normally not simulated).
ShellMaterials materials_from_config(const config::Tissue& tissue);

struct ShellOptions {
  std::string law = "fung";        // spring_laws() name
  // The in-plane model: "springs" (eq 17-18, one Fung spring per edge) or "triangles" (ours: a
  // constant-strain membrane triangle per face with eq 16's energy, W = s A0 (c/2)(e^Q - 1),
  // Q = alpha_f eps_f^2 + alpha_c eps_c^2 + alpha_c gamma^2 / 2, eps = 1 - 1/lambda (eq 17's
  // strain) along the triangle's fibre and cross-fibre directions and gamma the shear of that
  // pair (membrane.cc; the shear term, absent from eq 16, removes the zero-energy shear mode).
  // "triangles" takes law "fung" only; the edges stay as strain probes.
  std::string membrane = "springs";
  double fung_exponent_cap = 4;    // law "fung_tension": the largest exponent a eps^2 (ours)
  double fung_compression_fraction = 0;  // law "fung_tension": share of the (capped) Fung
                                         // stiffening kept in compression (ours)
  double active_min_fibre_stretch = 0;  // length-tension (ours): the active stress is tau f(lambda_f),
                                        // f = 1 - ((1 - lambda)/(1 - m))^2 on [m, 1], 0 below m,
                                        // 1 above 1; 0: f = 1 (the seed's eq 24)
  double active_cross_fibre_fraction = 0;  // (ours) a cross-fibre active stress k tau along
                                           // c0 = n x f0 besides the fibre's; 0: the seed's
  bool bending = true;
  double damping_per_ms = 0;       // gamma, mass-proportional
  double time_step_safety = 0.9;   // reported stable step = safety * 2 / omega_bound
  double strain_limit = 0.6;       // |eps| of any edge beyond it stops the run
  bool anchor_tagged_nodes = true; // nodes tagged geometry::kAnchor are held fixed
  int restep_interval = 8;         // substeps between energy-growth checks in advance()
  int threads = 1;                 // OpenMP threads of the spring + hinge loop (per-thread buffers)
  double cavity_plane_z_mm = 0;    // plane closing an open chamber for cavity_volume_mm3()
  double min_step_ms = 1e-4;       // a stable step below this (0.1 us, < the seed's 0.4 us) stops
                                   // the run with a diagnosis instead of crawling (ours)
  double area_floor = 0;              // J0 of the area floor (ours; 0: off, the seed's springs only);
                                      // in [0, 1)
  double area_floor_modulus_kpa = 10;  // kappa of the area floor (ours), > 0
  bool flat_rest_angles = false;   // theta0 = 0 on every hinge instead of the stress-free mesh's
                                   // (a shell that is flat at rest; verification, ours)
};

struct Energies {
  double kinetic_uj = 0;
  double elastic_uj = 0;         // in-plane springs and the area floor
  double bending_uj = 0;
  double active_uj = 0;          // sum tau_act s A lambda_f (the active tension's potential)
  double load_potential_uj = 0;  // -p V - sum F_ext . x
  double total_uj() const { return kinetic_uj + elastic_uj + bending_uj + active_uj + load_potential_uj; }
};

struct AdvanceStats {
  int substeps = 0;
  double smallest_dt_ms = 0, largest_dt_ms = 0;
};

// Per-edge spring data (stress-free mesh), exposed for diagnostics and tests.
struct EdgeSpring {
  std::int32_t i, j;
  double rest_length_mm;
  double cross_section_mm3;  // C
  double c_kpa, alpha;       // law parameters of this edge
};
struct BendingHinge {
  std::int32_t e0, e1, o1, o2;  // edge traversed e0 -> e1 by face 1 (e0, e1, o1); face 2 (e1, e0, o2)
  double theta0;                // rad
  double cos0, sin0;            // of theta0
  double kb_uj;
};

class ShellModel {
 public:
  // Builds masses, springs, hinges and active triangles from the stress-free mesh. Throws
  // InputError (naming the body and the item) for a negative or zero thickness, stiffness or
  // density, a zero-area triangle, a zero-length edge, an unknown law, a bad option, or a mesh
  // that carries a separate rest shape (TriMesh::rest_position_mm: build on
  // geometry::rest_shape(mesh) instead, so that no rest shape is silently ignored).
  ShellModel(const geometry::TriMesh& stress_free, const ShellMaterials& materials,
             const ShellOptions& options);

  // --- loads (held until changed) ---
  void set_external_loads(std::vector<Vec3> force_mn);  // size node_count(); caller's loads
  void set_cavity_pressure(double pressure_kpa);
  void set_active_tension(std::vector<double> tension_kpa);  // per node, >= 0 contracts
  // Replaces the springs' rest lengths (per spring, springs() order; a pre-stress, ours:
  // structure/prestress.h). Each must be finite and > 0; the masses, the springs' C, the hinges'
  // rest angles and the active triangles stay those of the stress-free mesh. Recomputes the forces.
  void set_rest_lengths_mm(const std::vector<double>& rest_length_mm);
  // Nodes held at their current position (besides the anchor-tagged ones).
  void fix_nodes(const std::vector<std::int32_t>& nodes);
  // Moves the fixed nodes rigidly: x = R X + t for their stress-free positions X (the anchors
  // follow a rigid body, e.g. the valvular plane); their velocity is set to v_i = (x_new - x_old)/T
  // spread over the next advance(T).
  void move_fixed_nodes(const Eigen::Matrix3d& rotation, const Vec3& translation_mm);
  // The seed's mitral limiter (no chordae, MODEL.md §5): the displacement of every free node from
  // its stress-free position along the unit vector `axis` is kept <= max_mm (one-sided; e.g.
  // axis = -z, towards the atrium, during systole). Applied after every drift: the excess is
  // projected away and the velocity component along axis, if outward, removed (inelastic, ours).
  void set_displacement_limit(const Vec3& axis, double max_mm);
  // The same, measured from `reference_mm` (one position per node) instead of the stress-free
  // positions: a body built in another shape than its stress-free one (the mitral leaflets built
  // closed over an open rest shape, geometry.mitral_rest_opening_mm, ours) keeps the seed's
  // limit on its displacement from the built, closed valve. Throws InputError on a wrong size.
  void set_displacement_limit(const Vec3& axis, double max_mm, std::vector<Vec3> reference_mm);
  // The positions the displacement limit measures from: empty until a limit is set, then the
  // given reference or the stress-free positions.
  const std::vector<Vec3>& displacement_limit_reference_mm() const { return limit_reference_mm_; }
  void clear_displacement_limit() { limit_on_ = false; }
  // A radial limiter (ours; the aortic cusps): every free node stays within
  // max(radius_mm, its stress-free distance) of the line through axis_point_mm along
  // axis_direction; applied after every drift like the displacement limit (the excess projected
  // away radially, an outward radial velocity removed).
  void set_radial_limit(const Vec3& axis_point_mm, const Vec3& axis_direction, double radius_mm);

  // --- time integration ---
  // Stable step (ms) at the current state: safety * 2 / sqrt(max over free nodes of the
  // Gershgorin row sum of the tangent stiffness / mass): springs (2 max(axial tangent,
  // tension / length) per end), hinges and active triangles; refreshed by every force
  // evaluation (no extra pass). Pressure (follower) stiffness is not included (ours: it is
  // O(p A / l), small beside the membrane's).
  double stable_step_ms() const;
  // What sets stable_step_ms(): "node N at (x, y, z) mm, Gershgorin row/mass R 1/ms^2; worst
  // edge a-b strain e" and, when one of that node's triangles is below half its stress-free
  // height, "triangle T (nodes ...) squeezed flat to r of its stress-free height" (diagnoses, ours).
  std::string stable_step_limiter() const;
  // Advances by T ms in n = ceil(T / stable step) equal substeps of velocity Verlet, loads held;
  // after every substep, when the (refreshed) stable step fell below the substep, the rest of T
  // is re-planned in equal smaller substeps (the Fung law stiffens). Throws InstabilityError("structure", "body B node
  // N ...", time) when an edge strain passes strain_limit or a value turns non-finite, or when
  // the kinetic energy grows by > 1e3 between two checks while exceeding the potential energy.
  AdvanceStats advance(double T_ms);
  // One velocity-Verlet substep of dt ms (no stability planning; the same checks).
  void substep(double dt_ms);

  // --- multi-body stepping (contact between bodies, solver/structure/contact.h) ---
  // substep(dt) is begin_substep(dt) then end_substep(dt). Between the two the positions are
  // those at the end of the substep, so forces that depend on other bodies can be set with
  // set_contact_loads() and enter the force evaluation of end_substep().
  void begin_substep(double dt_ms);  // half kick, drift, limiter, time += dt
  void end_substep(double dt_ms);    // forces at the new positions, half kick, strain check
  // Contact forces (mN, per node) and their stiffness (mN/mm, per node: the contribution to the
  // Gershgorin row sum of the tangent stiffness, so the stable step includes it). Held until
  // changed and added by every later force evaluation (end_substep, set_* or refresh_forces());
  // empty vectors remove them.
  void set_contact_loads(std::vector<Vec3> force_mn, std::vector<double> stiffness_mn_per_mm);
  void refresh_forces() { compute_forces(); }
  // Sets one free node's velocity (velocity-level constraints between bodies; fixed nodes keep
  // theirs). Forces are unchanged (they depend on positions only).
  void set_node_velocity(std::int32_t node, const Vec3& v_mm_per_ms) {
    if (!fixed_.at(node)) v_[node] = v_mm_per_ms;
  }
  // advance(T)'s bracket for a caller that sub-cycles several bodies in lockstep: begin_advance
  // gives the fixed nodes their velocity towards their targets over T; end_advance sets the
  // clock to t_end and puts moved fixed nodes exactly on their targets.
  void begin_advance(double T_ms);
  void end_advance(double t_end_ms);
  // The energy-growth check of advance(), called every restep_interval substeps: throws
  // InstabilityError when the kinetic energy grew by > 1e3 since the previous check, had also
  // grown by > 1e3 over the interval before (a motion starting from rest under a new load grows
  // like t^2 and does not pass twice; an explicit instability grows geometrically), and exceeds
  // the elastic + bending energy. Updates `watch`.
  struct EnergyWatch {
    double kinetic_uj = 0;
    bool grew = false;
  };
  void check_energy_growth(EnergyWatch& watch, double dt_ms, double dt_stable_ms) const;
  // Throws InstabilityError when stable_step_ms() < options().min_step_ms (as advance() does).
  void check_min_step() const;
  double kinetic_energy_uj() const;
  const ShellOptions& options() const { return options_; }
  // Lumped area of every node in the stress-free mesh (mm^2, 1/3 of its triangles').
  std::vector<double> node_areas_mm2() const;

  // --- state ---
  const std::string& name() const { return name_; }
  std::size_t node_count() const { return x_.size(); }
  double time_ms() const { return time_ms_; }
  const std::vector<Vec3>& positions_mm() const { return x_; }
  const std::vector<Vec3>& velocities_mm_per_ms() const { return v_; }
  const std::vector<double>& masses_mg() const { return mass_; }
  const std::vector<EdgeSpring>& springs() const { return springs_; }
  const std::vector<BendingHinge>& hinges() const { return hinges_; }
  const std::vector<std::uint8_t>& fixed() const { return fixed_; }
  const std::vector<double>& active_tension_kpa() const { return active_tension_kpa_; }  // per node, as set
  const geometry::TriMesh& stress_free_mesh() const { return mesh_; }
  const SpringLaw& law() const { return *law_; }
  // Replaces positions and velocities (tests, restarts); recomputes the forces.
  void set_state(std::vector<Vec3> x_mm, std::vector<Vec3> v_mm_per_ms);
  // Sets the clock (ms): with set_state, returns the body to a saved instant (strong coupling).
  void set_time_ms(double t_ms) { time_ms_ = t_ms; }

  Energies energies() const;
  // Total force (mN) on every node at the current state (internal + active + loads), as used by
  // the integrator (fixed nodes included: their entries are the reactions).
  const std::vector<Vec3>& forces_mn() const { return force_; }
  // Per-edge strains eps = (l - l0)/l at the current state.
  std::vector<double> edge_strains() const;
  double max_abs_strain() const;
  // Volume enclosed by the body and the plane z = cavity_plane_z_mm (closed bodies: any plane),
  // normals into the cavity; mm^3 (1000 mm^3 = 1 ml).
  double cavity_volume_mm3() const;

  // --- force kernels on arbitrary positions (tests: F = -grad W) ---
  double spring_energy(const std::vector<Vec3>& x) const;
  double bending_energy(const std::vector<Vec3>& x) const;
  double active_energy(const std::vector<Vec3>& x) const;
  double area_floor_energy(const std::vector<Vec3>& x) const;
  // The membrane triangles' energy (options.membrane = "triangles"; 0 otherwise).
  double membrane_energy(const std::vector<Vec3>& x) const;
  // Adds the membrane triangles' forces; with row != nullptr also their Gershgorin row sums.
  void add_membrane_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f, double* row = nullptr) const;
  // Adds the area floor's forces; with row != nullptr also its Gershgorin row sums (see
  // compute_forces).
  void add_area_floor_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f, double* row = nullptr) const;
  void add_spring_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const;
  void add_bending_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const;
  void add_active_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const;
  void add_pressure_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const;

 private:
  struct ActiveTriangle {
    std::int32_t a, b, c;
    double w0, w1;          // reference fibre f0 = w0 (X_b - X_a) + w1 (X_c - X_a)
    double v0, v1;          // reference cross-fibre c0 = n x f0, the same way
    double volume_mm3;      // s A (stress-free)
  };
  // A constant-strain membrane triangle (options.membrane = "triangles"): reference gradients of
  // its three shape functions in the (fibre, cross-fibre) frame of its stress-free plane, so that
  // F = sum_k x_k g_k^T (3 x 2) maps the reference fibre and cross-fibre directions to F f0, F c0.
  struct MembraneTriangle {
    std::int32_t node[3];
    double g[3][2];
    double volume_mm3;            // s A0
    double c_kpa, alpha_f, alpha_c;
  };
  void build_membrane(const ShellMaterials& materials);  // membrane_ from the stress-free mesh (membrane.cc)
  // InstabilityError naming the triangle whose deformed frame collapsed (membrane.cc).
  [[noreturn]] void throw_collapsed_triangle(const MembraneTriangle& t, const std::vector<Vec3>& x) const;
  void compute_forces();  // force_ at x_, records the worst strain
  void internal_forces_range(Vec3* f, double* row, std::int32_t s0, std::int32_t s1, std::int32_t h0, std::int32_t h1,
                             double& worst, std::int32_t& worst_edge, std::int32_t& bad) const;
  void check_state(const char* stage) const;
  [[noreturn]] void throw_instability(std::int32_t node, const std::string& what) const;
  double pressure_volume(const std::vector<Vec3>& x) const;

  std::string name_;
  geometry::TriMesh mesh_;
  ShellOptions options_;
  const SpringLaw* law_;
  std::vector<double> mass_, inv_mass_;
  std::vector<EdgeSpring> springs_;
  std::vector<BendingHinge> hinges_;
  std::vector<ActiveTriangle> active_;
  std::vector<MembraneTriangle> membrane_;  // empty unless options.membrane = "triangles"
  std::vector<double> active_tension_kpa_;  // per node
  std::vector<double> floor_area_mm2_, floor_kappa_s_;  // area floor: A0 and kappa s per triangle (empty: off)
  bool active_on_ = false;
  std::vector<std::uint8_t> fixed_;
  std::vector<Vec3> x_, v_, force_, external_;
  std::vector<Vec3> fixed_target_;  // where fixed nodes should be at the end of the advance
  std::vector<Vec3> contact_force_;    // set_contact_loads (empty: none)
  std::vector<double> contact_row_;
  bool moving_fixed_ = false;          // begin_advance found fixed nodes to move
  std::vector<double> row_;  // Gershgorin row sums of the tangent stiffness at x_ (compute_forces)
  std::vector<std::vector<Vec3>> thread_force_;  // per-thread buffers (threads > 1)
  std::vector<std::vector<double>> thread_row_;
  double omega2_ = 0;        // max over free nodes of row / mass
  double pressure_kpa_ = 0;
  bool limit_on_ = false;
  Vec3 limit_axis_ = Vec3::UnitZ();
  double limit_mm_ = 0;
  std::vector<Vec3> limit_reference_mm_;  // per node; the stress-free positions unless set
  bool radial_on_ = false;
  Vec3 radial_point_mm_ = Vec3::Zero(), radial_axis_ = Vec3::UnitZ();
  std::vector<double> radial_max_mm_;  // per node
  double time_ms_ = 0;
  // Worst edge at the last force evaluation.
  double worst_strain_ = 0;
  std::int32_t worst_edge_ = -1;
};

// Cavity volume (mm^3) of a surface with normals into the cavity, closed by the plane z = z_p:
// V = -sum_T (zbar_T - z_p) (A n)_z (exact; any z_p for a closed surface).
double cavity_volume_mm3(const std::vector<Vec3>& x, const std::vector<geometry::Tri>& tri,
                         double plane_z_mm);

}  // namespace systole::structure
