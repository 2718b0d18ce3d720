#include "solver/scene/ibm_scene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <complex>
#include <fstream>
#include <numbers>
#include <sstream>

#include "solver/core/errors.h"
#include "solver/fluid/fluid.h"
#include "solver/ibm/forcing.h"
#include "solver/ibm/loads.h"
#include "solver/ibm/plane_forcing.h"
#include "solver/ibm/shapes.h"

namespace systole::scene {
namespace {
constexpr double kPi = std::numbers::pi;
using Clock = std::chrono::steady_clock;
using ibm::Vec3;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// J0(z) by its power series (|z| ≲ 20 in double precision; Wo ≤ 15 here).
std::complex<double> bessel_j0(std::complex<double> z) {
  std::complex<double> term = 1, sum = 1;
  const std::complex<double> q = -0.25 * z * z;
  for (int m = 1; m < 200; ++m) {
    term *= q / static_cast<double>(m * m);
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum;
}

// J1 by its power series: Σ (−z²/4)^m (z/2) / (m! (m+1)!).
std::complex<double> bessel_j1(std::complex<double> z) {
  std::complex<double> term = 0.5 * z, sum = term;
  const std::complex<double> q = -0.25 * z * z;
  for (int m = 1; m < 200; ++m) {
    term *= q / static_cast<double>(m * (m + 1));
    sum += term;
    if (std::abs(term) < 1e-17 * std::abs(sum)) break;
  }
  return sum;
}

// Womersley's pipe flow for f_x = cos ωt (G = 1), radius R, ν: u(r, t) = Re{Û(r) e^{iωt}},
// Û = (1/(iω)) [1 − J0(λ r/R)/J0(λ)], λ = i^{3/2} Wo, Wo = R √(ω/ν).
struct WomersleyPipe {
  double radius, omega, wo;
  std::complex<double> lambda, j0_lambda;
  WomersleyPipe(double r, double w, double nu) : radius(r), omega(w), wo(r * std::sqrt(w / nu)) {
    lambda = std::polar(wo, 0.75 * kPi);
    j0_lambda = bessel_j0(lambda);
  }
  double velocity(double r, double t) const {
    const std::complex<double> i(0, 1);
    const std::complex<double> U = (1.0 / (i * omega)) * (1.0 - bessel_j0(lambda * (r / radius)) / j0_lambda);
    return std::real(U * std::exp(i * omega * t));
  }
  // ∂u/∂r at the wall: Û'(R) = (1/(iω)) (λ/R) J1(λ)/J0(λ) (J0' = −J1).
  double wall_gradient(double t) const {
    const std::complex<double> i(0, 1);
    const std::complex<double> dU = (1.0 / (i * omega)) * (lambda / radius) * bessel_j1(lambda) / j0_lambda;
    return std::real(dU * std::exp(i * omega * t));
  }
  double wall_gradient_amplitude() const {
    const std::complex<double> i(0, 1);
    return std::abs((1.0 / (i * omega)) * (lambda / radius) * bessel_j1(lambda) / j0_lambda);
  }
  double peak() const {  // amplitude at the axis
    const std::complex<double> i(0, 1);
    return std::abs((1.0 / (i * omega)) * (1.0 - 1.0 / j0_lambda));
  }
};

// The smallest icosphere subdivision with edges ≤ 0.7 h (then tiling level 1): ≈ 1.05 R / 2^s.
int sphere_subdivisions(double radius, double h) {
  int s = 0;
  while (1.05 * radius / std::pow(2.0, s) > 0.7 * h && s < 7) ++s;
  return s;
}

void check_spec(const IbmCaseSpec& s) {
  auto bad = [](const std::string& field, double v, const std::string& allowed) {
    std::ostringstream m;
    m << "ibm." << field << " = " << v << " is out of range " << allowed;
    throw InputError(m.str());
  };
  if (!(s.reynolds > 0 && s.reynolds <= 1e5)) bad("reynolds", s.reynolds, "(0, 1e5]");
  if (!(s.diameter_cells >= 4 && s.diameter_cells <= 128)) bad("diameter_cells", s.diameter_cells, "[4, 128]");
  if (!(s.box_diameters >= 1.5 && s.box_diameters <= 32)) bad("box_diameters", s.box_diameters, "[1.5, 32]");
  if (s.case_name == IbmCase::fixed_sphere && !(s.box_length_diameters >= 6 && s.box_length_diameters <= 64))
    bad("box_length_diameters", s.box_length_diameters, "[6, 64] (fringe 1.5 D + 2.5 D upstream + the wake)");
  if (!(s.end_time > 0 && s.end_time <= 1e4)) bad("end_time", s.end_time, "(0, 1e4]");
  if (!(s.frequency > 0)) bad("frequency", s.frequency, "(0, inf)");
  if (!(s.amplitude > 0 && s.amplitude <= 0.5)) bad("amplitude", s.amplitude, "(0, 0.5] diameters");
  if (!(s.retraction_cells >= 0 && s.retraction_cells <= 1)) bad("retraction_cells", s.retraction_cells, "[0, 1]");
  if (!(s.womersley_number > 0 && s.womersley_number <= 15)) bad("womersley_number", s.womersley_number, "(0, 15]");
  if (s.samples < 1) bad("samples", s.samples, "[1, inf)");
}

// The case's box of cubic cells of side h: the spheres and the orifice plate in a cube of side
// box_diameters (fixed_sphere: box_length_diameters long in x), the pipe in a 0.5 D × 1.5 D × 1.5 D slab.
grid::BoxSpec ibm_box(const IbmCaseSpec& spec, bool sphere, bool orifice, double h) {
  grid::BoxSpec box;
  if (sphere || orifice) {
    box.nx = box.ny = box.nz = static_cast<int>(std::lround(spec.box_diameters * spec.diameter_cells));
    if (spec.case_name == IbmCase::fixed_sphere)
      box.nx = static_cast<int>(std::lround(spec.box_length_diameters * spec.diameter_cells));
  } else {
    box.nx = std::max(4, static_cast<int>(std::lround(0.5 * spec.diameter_cells)));
    box.ny = box.nz = static_cast<int>(std::lround(1.5 * spec.diameter_cells));
  }
  box.lx = box.nx * h;
  box.ly = box.ny * h;
  box.lz = box.nz * h;
  return box;
}

// The fluid's parameters: Re, CFL, Δt cap; no-slip z walls for the orifice's duct, free-slip otherwise.
fluid::FluidParameters ibm_fluid_parameters(const IbmCaseSpec& spec, bool orifice, double time_scale_s) {
  fluid::FluidParameters fp;
  fp.reynolds = spec.reynolds;
  fp.cfl = spec.cfl;
  fp.max_dt = spec.max_dt;
  fp.bottom_wall.kind = fp.top_wall.kind = orifice ? fluid::WallKind::no_slip : fluid::WallKind::free_slip;  // (ours)
  fp.time_scale_s = time_scale_s;
  return fp;
}

// One verification case from set-up to results (ibm_scene.h). The stages are methods over the
// case's state; the fluid's body force holds `this`, so the object never moves.
class IbmCaseRun {
 public:
  // Builds grid, fluid, body, forcing, the step's body force and the initial state; t = 0.
  IbmCaseRun(const IbmCaseSpec& spec, MPI_Comm comm, double time_scale_s);
  IbmCaseRun(const IbmCaseRun&) = delete;
  IbmCaseRun& operator=(const IbmCaseRun&) = delete;
  // Marches to end_time in spec.samples intervals, sampling at each (progress and cancel polls
  // there); returns the metrics, the series and, with output_dir, the fields and markers.
  RunResult run(const std::function<void(const ProgressReport&)>& progress, const std::function<bool()>& cancel);

 private:
  void add_body();
  void step_body_force(const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f);
  void set_initial_state();
  double pipe_error_now() const;
  void after_step();
  double flow_rate() const;
  Vec3 sample_force();
  void sample_pipe();
  void sample_orifice(const Vec3& mean_force);
  void report_progress(const std::function<void(const ProgressReport&)>& progress, int s) const;
  bool cancelled_anywhere(const std::function<bool()>& cancel) const;
  void common_metrics(std::map<std::string, double>& M) const;
  void case_metrics(std::map<std::string, double>& M) const;
  void write_outputs(std::map<std::string, double>& M) const;

  // Prescribed motion (oscillating sphere): x_c = x₀ + A(1 − cos ωt), its velocity and acceleration.
  double displacement(double t) const { return A * (1 - std::cos(omega * t)); }
  double body_velocity(double t) const { return A * omega * std::sin(omega * t); }
  double body_acceleration(double t) const { return A * omega * omega * std::cos(omega * t); }

  const IbmCaseSpec& spec;
  const MPI_Comm comm;
  const double time_scale_s;
  const Clock::time_point start = Clock::now();
  const bool orifice = spec.case_name == IbmCase::orifice_plate;
  const bool sphere = spec.case_name == IbmCase::fixed_sphere || spec.case_name == IbmCase::oscillating_sphere;
  const double h = 1.0 / spec.diameter_cells;
  // ---- grid (cubic cells of side h), fluid ----
  const grid::BoxSpec box = ibm_box(spec, sphere, orifice, h);
  const grid::Grid g{box};
  const grid::Slabs slabs{g, comm};
  fluid::FluidSolver fluid{slabs, ibm_fluid_parameters(spec, orifice, time_scale_s)};
  // ---- body (add_body) ----
  ibm::Markers markers{g};
  Vec3 centre = Vec3(box.lx / 2, box.ly / 2, box.lz / 2);
  // fixed_sphere: the fringe (x ∈ [0, w]) feeds the uniform stream; the sphere sits 2.5 D
  // downstream of it (ours), leaving box_length − w − 2.5 D for the wake.
  const double fringe_width = 1.5;
  double omega = 2 * kPi * spec.frequency;
  std::unique_ptr<WomersleyPipe> pipe;
  int body = 0, cover_body = -1;
  std::unique_ptr<ibm::PlaneForcing> plate_eq4, cover_eq4;  // orifice_plate by eq 4
  double drive_density = 0;                                  // orifice_plate: G
  std::vector<Vec3> reference_nodes;
  double body_volume = 0;
  std::unique_ptr<ibm::DirectForcing> forcing;
  const double A = spec.amplitude;
  // ---- the step's body force (step_body_force) ----
  double v_x = 0, v_z = 0;      // x/y faces, interior z faces
  Vec3 uniform = Vec3::Zero();  // last step's uniform force (what the markers saw)
  Vec3 body_force_total = Vec3::Zero();
  // Impulse ∫F_h dt since the last sample: the sampled force is its mean over the interval.
  // (The force of one step contains the previous step's residual slip over that step's Δt,
  // −Σ(u^n − V_b)ΔV_b/Δt; the step that lands on a sample time is shortened, so its force
  // alone was off by tens of percent (docs/ibm.md): only the impulse is independent of Δt.)
  Vec3 impulse = Vec3::Zero(), last_mean_force = Vec3::Zero();
  double impulse_time = 0;
  double ibm_seconds = 0;
  double added_num = 0, added_den = 0;  // ∫F_h a dt, ∫a² dt
  const double first_period = 1.0 / spec.frequency;
  double end_time = spec.end_time;
  int periods = 0;
  // ---- sampling ----
  Series ts{"time_s", "s", {}}, fx{"force_x", "rho U^2 D^2", {}}, fy{"force_y", "rho U^2 D^2", {}},
      fz{"force_z", "rho U^2 D^2", {}}, slip_series{"slip_rms", "U", {}};
  std::vector<double> drag_samples;
  double pipe_error = 0;
  // Womersley: the markers' wall shear stress (eq 27 extrapolated to the wall from probes at h
  // and 2h, ibm::wall_shear_stress; and the loads' single-probe value) against the exact
  // |τ_w| = Re⁻¹ |∂u/∂r (R, t)|, largest difference over the samples.
  double wss_error = 0, wss_probe_error = 0;
  Series wss_series{"wall_shear_stress_mean", "rho U^2", {}}, wss_exact_series{"wall_shear_stress_exact", "rho U^2", {}};
  bool cancelled = false;
  ibm::SlipStats slip;
  // Surface loads (eq 11, 14) after every step on the sphere cases: the second estimate of the
  // force on the body, independent of the rigid-interior correction of F_h.
  Vec3 loads_force = Vec3::Zero();
  double loads_num = 0, loads_den = 0;
  std::vector<double> drag_loads_samples;
  // orifice_plate: the volume flux through the duct (the same through every x-plane: periodic
  // in x, divergence-free), measured on the x-faces i = 0.
  Series flow_series{"flow_rate", "U D^2", {}};
  double flow_open = 0, plate_force_open = 0, switch_time = -1;
};

IbmCaseRun::IbmCaseRun(const IbmCaseSpec& spec_in, MPI_Comm comm_in, double time_scale_s_in)
    : spec(spec_in), comm(comm_in), time_scale_s(time_scale_s_in) {
  add_body();
  reference_nodes = markers.bodies()[body].tiled.position_mm;
  body_volume = sphere ? ibm::signed_volume(markers.bodies()[body].tiled) : 0.0;
  ibm::ForcingParameters fpar;
  fpar.iterations = spec.forcing_iterations;
  fpar.carry_over = spec.carry_over_force;
  forcing = std::make_unique<ibm::DirectForcing>(slabs, markers, fpar);

  // ---- the step's body force: IB forcing (eq 3, 8) + the case's uniform force ----
  v_x = g.lx() * g.ly() * g.lz(), v_z = g.lx() * g.ly() * (g.lz() - g.dz());
  fluid.set_body_force([this](const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
    step_body_force(c, uh, f);
  });

  set_initial_state();
  if (spec.case_name == IbmCase::oscillating_sphere || spec.case_name == IbmCase::womersley_pipe) {
    const double period = 2 * kPi / omega;
    periods = std::max(spec.case_name == IbmCase::oscillating_sphere ? 2 : 1,
                       static_cast<int>(std::ceil(spec.end_time / period - 1e-9)));
    end_time = periods * period;
  }
}

// The case's markers: the sphere (icosphere, tiling level 1), the orifice plate and its cover
// (the cover off; with first_node_plane both as eq 4 planes instead), or the pipe's tube (and
// the Womersley solution it is checked against).
void IbmCaseRun::add_body() {
  ibm::BodyOptions bo;
  bo.mm_per_unit = 1.0;  // meshes below are built in grid units
  bo.retraction_cells = spec.retraction_cells;
  if (spec.case_name == IbmCase::fixed_sphere) centre.x() = fringe_width + 2.5;
  if (sphere) {
    bo.normals = ibm::ExpectedNormals::outward;
    // Tiling level 1: the icosphere is already sized for tile edges ≈ 0.7 h (D/h = 10: mean
    // 0.75 h, longest 0.82 h; always < 0.88 h < h). The automatic level (longest edge ≤ 0.7 h)
    // went to level 2, 4× the markers (≈ 16 per h²) for the same drag (C_D 1.3462 vs 1.3479).
    bo.tiling_level = 1;
    body = markers.add_body(ibm::sphere_mesh(centre, 0.5, sphere_subdivisions(0.5, h)), "sphere", bo);
  } else if (orifice) {
    // The plate (two-sided: blood on both faces, no retraction of its faces) with the hole's rim
    // moved out by r_d h (the retraction applied to the edge), and the cover filling the hole.
    bo.normals = ibm::ExpectedNormals::unchecked;
    bo.sides = ibm::Sides::two;
    bo.retraction_cells = 0;
    const double hole = 0.5 + spec.retraction_cells * h;
    const double z_margin = h * (1 + 1e-9);  // the nodes must stay >= Δz off the walls (round-off)
    // Quads of side ≤ 0.7 h (diagonals ≤ 0.99 h < h), tiling level 1: ≈ 4 markers per h².
    const int qy = static_cast<int>(std::ceil(box.ly / (0.7 * h)));
    const int qz = static_cast<int>(std::ceil((box.lz - 2 * z_margin) / (0.7 * h)));
    bo.tiling_level = 1;
    for (ibm::PlatePart part : {ibm::PlatePart::plate, ibm::PlatePart::cover}) {
      const int id = markers.add_body(ibm::perforated_plate_x_mesh(box.lx / 2, 0, box.ly, z_margin, box.lz - 2 * z_margin,
                                                                   centre.y(), centre.z(), hole, qy, qz, part),
                                      part == ibm::PlatePart::plate ? "orifice plate" : "orifice cover", bo);
      (part == ibm::PlatePart::plate ? body : cover_body) = id;
    }
    markers.set_active(cover_body, false);
    if (spec.first_node_plane) {  // eq 4 instead: the markers stay off (kept for the CSV)
      markers.set_active(body, false);
      const double yc = centre.y(), zc = centre.z();
      plate_eq4 = std::make_unique<ibm::PlaneForcing>(
          slabs, ibm::RigidPlane{0, box.lx / 2, [=](double y, double z) { return std::hypot(y - yc, z - zc) >= 0.5; }});
      cover_eq4 = std::make_unique<ibm::PlaneForcing>(
          slabs, ibm::RigidPlane{0, box.lx / 2, [=](double y, double z) { return std::hypot(y - yc, z - zc) < 0.5; }});
      cover_eq4->set_active(false);
    }
    drive_density = 6 * kPi / (box.lx * spec.reynolds);
  } else {
    bo.normals = ibm::ExpectedNormals::unchecked;  // an open tube
    // Quads of side ≤ 0.7h/√2: the diagonals meet the 0.7h tile target at tiling level 1.
    const double side = 0.7 * h / std::sqrt(2.0);
    const int around = static_cast<int>(std::ceil(kPi / side));
    const int axial = std::max(1, static_cast<int>(std::ceil(box.lx / side)));
    body = markers.add_body(ibm::tube_mesh(0, box.lx, centre.y(), centre.z(), 0.5, axial, around), "tube", bo);
    omega = spec.womersley_number * spec.womersley_number / (0.25 * spec.reynolds);  // Wo = R√(ωRe)
    pipe = std::make_unique<WomersleyPipe>(0.5, omega, 1.0 / spec.reynolds);
  }
}

// The step's body force f on [t, t + Δt] from the predicted velocity û: IB forcing (eq 3, 8),
// eq 4 planes, the case's uniform force and the fixed sphere's fringe; accumulates the force on
// the body (Uhlmann 2005), its impulse and the oscillating sphere's ∫F_h a dt, ∫a² dt.
void IbmCaseRun::step_body_force(const fluid::StepContext& c, const fluid::Velocity& uh, fluid::Velocity& f) {
  const auto t0 = Clock::now();
  const double t1 = c.time + c.dt;
  if (spec.case_name == IbmCase::oscillating_sphere) {
    std::vector<Vec3> pos(reference_nodes.size()), vel(reference_nodes.size(), Vec3(body_velocity(t1), 0, 0));
    for (std::size_t n = 0; n < pos.size(); ++n) pos[n] = reference_nodes[n] + Vec3(displacement(t1), 0, 0);
    markers.set_nodes(body, pos, vel);
    forcing->markers_moved();
  }
  Vec3 drive = Vec3::Zero();
  if (spec.case_name == IbmCase::womersley_pipe) drive = Vec3(std::cos(omega * (c.time + 0.5 * c.dt)), 0, 0);
  if (orifice) drive = Vec3(drive_density, 0, 0);
  const ibm::ForcingReport& r =
      forcing->apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, sphere ? uniform : drive);
  Vec3 eq4_force = Vec3::Zero();
  if (plate_eq4) {
    eq4_force += plate_eq4->apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, drive);
    eq4_force += cover_eq4->apply(c.dt, {uh.u, uh.v, uh.w}, {f.u, f.v, f.w}, drive);
  }
  if (spec.case_name == IbmCase::oscillating_sphere) {
    // g = −F_IB / V: the box-mean momentum is unchanged by the step's forcing (ours).
    drive = Vec3(-r.total_force.x() / v_x, -r.total_force.y() / v_x, -r.total_force.z() / v_z);
    uniform = drive;
  }
  if (spec.case_name == IbmCase::fixed_sphere) {
    // Fringe region (ours; Nordström, Nordin & Henningson 1999 SIAM J. Sci. Comput. 20:1365):
    // f += s(x)(u∞ − û)/Δt with s = sin²(πx/w) on x ∈ [0, w], u∞ = (1, 0, 0): the wake
    // leaving through x = L re-enters as the uniform stream.
    auto strength = [&](double x) { return x < fringe_width ? std::pow(std::sin(kPi * x / fringe_width), 2) : 0.0; };
    for (int k = 0; k < f.u.k_count(); ++k) {
      const bool wall = slabs.k_begin() + k == 0;
      for (int j = 0; j < g.ny(); ++j)
        for (int i = 0; i < g.nx(); ++i) {
          const double su = strength(g.x(grid::Location::x_face, i)), sc = strength(g.x(grid::Location::cell, i));
          if (su > 0) f.u(i, j, k) += su * (1.0 - uh.u(i, j, k)) / c.dt;
          if (sc > 0) {
            f.v(i, j, k) -= sc * uh.v(i, j, k) / c.dt;
            if (!wall) f.w(i, j, k) -= sc * uh.w(i, j, k) / c.dt;
          }
        }
    }
  }
  for (int k = 0; k < f.u.k_count(); ++k) {
    const bool wall = slabs.k_begin() + k == 0;
    for (int j = 0; j < g.ny(); ++j)
      for (int i = 0; i < g.nx(); ++i) {
        f.u(i, j, k) += drive.x();
        f.v(i, j, k) += drive.y();
        if (!wall) f.w(i, j, k) += drive.z();
      }
  }
  // Force on the body (Uhlmann 2005): −Σ F_b ΔV_b + d/dt ∫_body u dV (rigid: V_s a).
  const double a1 = spec.case_name == IbmCase::oscillating_sphere ? body_acceleration(t1) : 0.0;
  body_force_total = -r.total_force - eq4_force + Vec3(body_volume * a1, 0, 0);
  impulse += body_force_total * c.dt;
  impulse_time += c.dt;
  if (spec.case_name == IbmCase::oscillating_sphere && c.time >= first_period * (1 - 1e-12)) {
    added_num += body_force_total.x() * a1 * c.dt;
    added_den += a1 * a1 * c.dt;
  }
  ibm_seconds += seconds_since(t0);
}

// Initial velocity: the uniform stream (fixed_sphere), Womersley's solution at t = 0 inside the
// tube (womersley_pipe), rest otherwise.
void IbmCaseRun::set_initial_state() {
  if (spec.case_name == IbmCase::fixed_sphere) {
    fluid.set_velocity([](double, double, double) { return 1.0; }, [](double, double, double) { return 0.0; },
                       [](double, double, double) { return 0.0; });
  } else if (spec.case_name == IbmCase::womersley_pipe) {
    const double yc = centre.y(), zc = centre.z();
    fluid.set_velocity(
        [&](double, double y, double z) {
          const double r = std::hypot(y - yc, z - zc);
          return r < 0.5 ? pipe->velocity(r, 0.0) : 0.0;
        },
        [](double, double, double) { return 0.0; }, [](double, double, double) { return 0.0; });
  }
}

// womersley_pipe: max |u − u_exact| over the x-faces inside the tube, over all ranks (collective).
double IbmCaseRun::pipe_error_now() const {
  double e = 0;
  const auto& u = fluid.velocity().u;
  for (int k = 0; k < u.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j) {
      const double r = std::hypot(g.y(grid::Location::x_face, j) - centre.y(),
                                  g.z(grid::Location::x_face, slabs.k_begin() + k) - centre.z());
      if (r >= 0.5) continue;
      const double ue = pipe->velocity(r, fluid.time());
      for (int i = 0; i < g.nx(); ++i) e = std::max(e, std::abs(u(i, j, k) - ue));
    }
  double out = 0;
  MPI_Allreduce(&e, &out, 1, MPI_DOUBLE, MPI_MAX, comm);
  return out;
}

// Sphere cases: the surface loads (eq 11, 14) of the step just taken; oscillating_sphere after
// the first period also accumulates ∫F_loads a dt, ∫a² dt.
void IbmCaseRun::after_step() {
  if (!sphere) return;
  const fluid::Velocity& V = fluid.velocity();
  const double t = fluid.time();
  const double a = spec.case_name == IbmCase::oscillating_sphere ? body_acceleration(t) : 0.0;
  std::vector<Vec3> acc(markers.size(), Vec3(a, 0, 0));
  loads_force = ibm::compute_loads(forcing->transfer(), {V.u, V.v, V.w}, fluid.pressure(), spec.reynolds, acc).total_force;
  if (spec.case_name == IbmCase::oscillating_sphere && t - fluid.last_dt() >= first_period * (1 - 1e-12)) {
    loads_num += loads_force.x() * a * fluid.last_dt();
    loads_den += a * a * fluid.last_dt();
  }
}

// orifice_plate: the volume flux through the x-faces i = 0, summed over all ranks (collective).
double IbmCaseRun::flow_rate() const {
  const auto& u = fluid.velocity().u;
  double q = 0;
  for (int k = 0; k < u.k_count(); ++k)
    for (int j = 0; j < g.ny(); ++j) q += u(0, j, k);
  q *= g.dy() * g.dz();
  double out = 0;
  MPI_Allreduce(&q, &out, 1, MPI_DOUBLE, MPI_SUM, comm);
  return out;
}

// At a sample: the slip, the interval's mean force on the body (impulse / time, then reset),
// the force series and, on fixed_sphere, the drag samples (C_D = F_x / (½ π/4)).
Vec3 IbmCaseRun::sample_force() {
  const fluid::Velocity& V = fluid.velocity();
  slip = forcing->slip({V.u, V.v, V.w});
  const Vec3 mean_force = impulse_time > 0 ? Vec3(impulse / impulse_time) : body_force_total;
  impulse = Vec3::Zero();
  impulse_time = 0;
  last_mean_force = mean_force;
  ts.values.push_back(fluid.time() * time_scale_s);
  fx.values.push_back(mean_force.x());
  fy.values.push_back(mean_force.y());
  fz.values.push_back(mean_force.z());
  slip_series.values.push_back(slip.rms);
  if (spec.case_name == IbmCase::fixed_sphere) {
    drag_samples.push_back(mean_force.x() / (0.125 * kPi));
    drag_loads_samples.push_back(loads_force.x() / (0.125 * kPi));
  }
  return mean_force;
}

// womersley_pipe at a sample: the velocity error and the markers' mean wall shear stress (eq 27)
// against the exact |τ_w|; collective (pipe_error_now).
void IbmCaseRun::sample_pipe() {
  const fluid::Velocity& V = fluid.velocity();
  pipe_error = std::max(pipe_error, pipe_error_now());
  const ibm::MarkerLoads loads = ibm::compute_loads(forcing->transfer(), {V.u, V.v, V.w}, fluid.pressure(), spec.reynolds);
  const ibm::WallShear wall = ibm::wall_shear_stress(forcing->transfer(), {V.u, V.v, V.w}, fluid.pressure(), spec.reynolds);
  double sum = 0, sum_probe = 0;
  std::size_t n = 0;
  for (std::size_t b = 0; b < loads.wss.size(); ++b)
    if (markers.active(b)) sum += wall.plus[b], sum_probe += loads.wss[b], ++n;
  const double mean = n ? sum / static_cast<double>(n) : 0.0, mean_probe = n ? sum_probe / static_cast<double>(n) : 0.0;
  const double exact = std::abs(pipe->wall_gradient(fluid.time())) / spec.reynolds;
  wss_series.values.push_back(mean);
  wss_exact_series.values.push_back(exact);
  wss_error = std::max(wss_error, std::abs(mean - exact));
  wss_probe_error = std::max(wss_probe_error, std::abs(mean_probe - exact));
}

// orifice_plate at a sample: the flow rate (collective); at the first sample at or after
// end_time/2 the cover switches on.
void IbmCaseRun::sample_orifice(const Vec3& mean_force) {
  flow_series.values.push_back(flow_rate());
  if (switch_time < 0 && fluid.time() >= 0.5 * end_time * (1 - 1e-12)) {
    // Close the opening (the seed's vein ostia, MODEL.md §2): the cover's markers (or its
    // eq 4 plane) switch on for the second half of the run.
    flow_open = flow_series.values.back();
    plate_force_open = mean_force.x();
    switch_time = fluid.time();
    if (cover_eq4) {
      cover_eq4->set_active(true);
    } else {
      markers.set_active(cover_body, true);
      forcing->markers_moved();
    }
  }
}

// Progress after sample s of spec.samples (one "beat").
void IbmCaseRun::report_progress(const std::function<void(const ProgressReport&)>& progress, int s) const {
  ProgressReport rep;
  rep.simulated_time_s = fluid.time() * time_scale_s;
  rep.beat = 1;
  rep.beats_total = 1;
  rep.fraction = static_cast<double>(s) / spec.samples;
  rep.message = std::string("ibm ") + to_string(spec.case_name);
  if (!drag_samples.empty())  // the latest interval's mean drag, so a long run shows its trend (ours)
    rep.message += " drag_coefficient " + std::to_string(drag_samples.back());
  progress(rep);
}

// True when any rank's cancel() is true (collective).
bool IbmCaseRun::cancelled_anywhere(const std::function<bool()>& cancel) const {
  int mine = cancel() ? 1 : 0, any = 0;
  MPI_Allreduce(&mine, &any, 1, MPI_INT, MPI_MAX, comm);
  return any != 0;
}

RunResult IbmCaseRun::run(const std::function<void(const ProgressReport&)>& progress,
                          const std::function<bool()>& cancel) {
  // ---- march, sampling ----
  for (int s = 1; s <= spec.samples; ++s) {
    const double t_sample = end_time * s / spec.samples;
    while (fluid.time() < t_sample * (1 - 1e-14) - 1e-300) {
      fluid.advance(t_sample);
      if (spec.case_name == IbmCase::oscillating_sphere) after_step();  // every step: ∫F a dt
    }
    if (spec.case_name == IbmCase::fixed_sphere) after_step();          // at the samples
    const Vec3 mean_force = sample_force();
    if (pipe) sample_pipe();
    if (orifice) sample_orifice(mean_force);
    if (progress) report_progress(progress, s);
    if (cancel && cancelled_anywhere(cancel)) {
      cancelled = true;
      break;
    }
  }
  RunResult result;
  auto& M = result.metrics;
  common_metrics(M);
  case_metrics(M);
  write_outputs(M);
  for (const std::string& w : markers.warnings()) result.notes.push_back(w);
  result.series = {std::move(ts), std::move(fx), std::move(fy), std::move(fz), std::move(slip_series)};
  if (orifice) result.series.push_back(std::move(flow_series));
  if (pipe) {
    result.series.push_back(std::move(wss_series));
    result.series.push_back(std::move(wss_exact_series));
  }
  return result;
}

// The metrics every case reports (ibm_scene.h): run size, slip, divergence, wall times.
void IbmCaseRun::common_metrics(std::map<std::string, double>& M) const {
  const fluid::FlowDiagnostics d = fluid.diagnostics();
  int ranks = 1;
  MPI_Comm_size(comm, &ranks);
  M["steps"] = static_cast<double>(fluid.steps());
  M["end_time"] = fluid.time();
  M["cells"] = static_cast<double>(g.cells());
  M["ranks"] = ranks;
  M["markers"] = static_cast<double>(markers.size());
  M["tiling_level"] = markers.bodies()[body].tiling_level;
  M["slip_rms_final"] = slip.rms;
  M["slip_max_final"] = slip.max;
  {
    const auto& v = slip_series.values;
    const std::size_t from = v.size() / 2;
    double mean = 0;
    for (std::size_t q = from; q < v.size(); ++q) mean += v[q];
    M["slip_rms_mean"] = mean / static_cast<double>(v.size() - from);
  }
  M["forcing_slip_rms_final"] = forcing->last_report().slip_before.rms;
  M["max_divergence_final"] = d.max_divergence;
  M["wall_time_ibm_s"] = ibm_seconds;
  M["wall_time_fluid_s"] = seconds_since(start) - ibm_seconds;
  M["cancelled"] = cancelled ? 1 : 0;
  M["reynolds"] = spec.reynolds;
  M["diameter_cells"] = spec.diameter_cells;
}

// The case's verification metrics (ibm_scene.h): drag (fixed_sphere), added mass against
// unsteady Stokes (oscillating_sphere), open/closed flow (orifice_plate), Womersley errors.
void IbmCaseRun::case_metrics(std::map<std::string, double>& M) const {
  if (spec.case_name == IbmCase::fixed_sphere) {
    const std::size_t n = drag_samples.size(), from = n - std::max<std::size_t>(1, n / 5);
    double mean = 0;
    for (std::size_t q = from; q < n; ++q) mean += drag_samples[q];
    M["drag_coefficient"] = mean / static_cast<double>(n - from);
    M["drag_coefficient_final"] = drag_samples.back();
    double mean_loads = 0;
    for (std::size_t q = from; q < n; ++q) mean_loads += drag_loads_samples[q];
    M["drag_coefficient_loads"] = mean_loads / static_cast<double>(n - from);
    M["lift_coefficient_final"] = std::hypot(last_mean_force.y(), last_mean_force.z()) / (0.125 * kPi);
    M["blockage_area_ratio"] = (kPi / 4) / (g.ly() * g.lz());
  } else if (spec.case_name == IbmCase::oscillating_sphere) {
    const double delta = std::sqrt(2.0 / (spec.reynolds * omega));
    const double ca = added_den > 0 ? -added_num / (body_volume * added_den) : 0.0;
    const double ref = 0.5 + 9 * delta / (4 * 0.5);
    M["added_mass_coefficient"] = ca;
    M["added_mass_coefficient_stokes"] = ref;
    M["added_mass_relative_error"] = (ca - ref) / ref;
    const double ca_loads = loads_den > 0 ? -loads_num / (body_volume * loads_den) : 0.0;
    M["added_mass_coefficient_loads"] = ca_loads;
    M["added_mass_loads_relative_error"] = (ca_loads - ref) / ref;
    M["stokes_layer_thickness"] = delta;
    M["periods"] = periods;
    M["volume_fraction"] = (kPi / 6) / (g.lx() * g.ly() * g.lz());
  } else if (orifice) {
    const double closed = flow_series.values.empty() ? 0.0 : flow_series.values.back();
    M["flow_rate_open"] = flow_open;
    M["flow_rate_closed"] = closed;
    M["closed_to_open_flow_ratio"] = flow_open != 0 ? closed / flow_open : 0.0;
    M["hole_mean_velocity_open"] = flow_open / (kPi / 4);
    M["plate_force_x_open"] = plate_force_open;
    M["cover_switch_time"] = switch_time;
    M["driving_force_density"] = drive_density;
    M["first_node_plane"] = spec.first_node_plane ? 1 : 0;
  } else {
    M["error_linf_relative"] = pipe_error / pipe->peak();
    M["reference_peak_velocity"] = pipe->peak();
    M["reference_wall_shear_amplitude"] = pipe->wall_gradient_amplitude() / spec.reynolds;
    M["wall_shear_error_linf_relative"] = wss_error / (pipe->wall_gradient_amplitude() / spec.reynolds);
    M["wall_shear_probe_error_linf_relative"] = wss_probe_error / (pipe->wall_gradient_amplitude() / spec.reynolds);
    M["periods"] = periods;
    M["womersley_number"] = pipe->wo;
  }
}

// With output_dir and not cancelled: ibm_fields.h5 (all ranks) and ibm_markers.csv (rank 0);
// sets fields_written.
void IbmCaseRun::write_outputs(std::map<std::string, double>& M) const {
  M["fields_written"] = 0;
  if (!spec.output_dir.empty() && !cancelled) {
    std::filesystem::create_directories(spec.output_dir);
    fluid.write_fields(spec.output_dir / "ibm_fields.h5");
    int rank = 0;
    MPI_Comm_rank(comm, &rank);
    if (rank == 0) {
      std::ofstream csv(spec.output_dir / "ibm_markers.csv");
      csv << "x,y,z,normal_x,normal_y,normal_z,area,force_density_x,force_density_y,force_density_z\n";
      const ibm::MarkerArrays& m = markers.markers();
      for (std::size_t b = 0; b < m.size(); ++b) {
        const Vec3& F = forcing->force_density()[b];
        csv << m.position[b].x() << ',' << m.position[b].y() << ',' << m.position[b].z() << ',' << m.normal[b].x()
            << ',' << m.normal[b].y() << ',' << m.normal[b].z() << ',' << m.area[b] << ',' << F.x() << ',' << F.y()
            << ',' << F.z() << '\n';
      }
    }
    M["fields_written"] = 1;
  }
}

}  // namespace

const char* to_string(IbmCase c) {
  switch (c) {
    case IbmCase::fixed_sphere: return "fixed_sphere";
    case IbmCase::oscillating_sphere: return "oscillating_sphere";
    case IbmCase::womersley_pipe: return "womersley_pipe";
    case IbmCase::orifice_plate: return "orifice_plate";
  }
  return "?";
}

IbmCase parse_ibm_case(const std::string& name) {
  for (IbmCase c : {IbmCase::fixed_sphere, IbmCase::oscillating_sphere, IbmCase::womersley_pipe, IbmCase::orifice_plate})
    if (name == to_string(c)) return c;
  throw InputError("ibm.verification_case = '" + name +
                   "' is unknown; known: fixed_sphere, oscillating_sphere, womersley_pipe, orifice_plate");
}

RunResult run_ibm_case(const IbmCaseSpec& spec, MPI_Comm comm, double time_scale_s,
                       const std::function<void(const ProgressReport&)>& progress,
                       const std::function<bool()>& cancel) {
  check_spec(spec);
  IbmCaseRun run(spec, comm, time_scale_s);
  return run.run(progress, cancel);
}

RunResult run_ibm(const config::Scenario& scenario, RunControl& control) {
  int mpi_ready = 0;
  MPI_Initialized(&mpi_ready);
  if (!mpi_ready) throw std::logic_error("scene 'ibm' needs MPI: the caller must call MPI_Init first");
  const config::Ibm& c = scenario.ibm;
  IbmCaseSpec spec;
  spec.case_name = parse_ibm_case(c.verification_case);
  spec.reynolds = c.reynolds;
  spec.diameter_cells = c.diameter_cells;
  spec.box_diameters = c.box_diameters;
  spec.box_length_diameters = c.box_length_diameters;
  spec.end_time = c.end_time_convective;
  spec.frequency = c.oscillation_frequency;
  spec.amplitude = c.oscillation_amplitude_diameters;
  spec.womersley_number = c.womersley_number;
  spec.forcing_iterations = c.forcing_iterations;
  spec.cfl = c.cfl;
  spec.retraction_cells = c.marker_retraction_cells;
  spec.carry_over_force = c.forcing_carry_over;
  spec.first_node_plane = c.valvular_plane_method == "first_node";
  spec.samples = 50;
  if (c.write_fields) spec.output_dir = control.output_directory();
  RunResult result = run_ibm_case(
      spec, MPI_COMM_WORLD, 1.0, [&](const ProgressReport& report) { control.on_progress(report); },
      [&] { return control.cancel_requested(); });
  if (result.metrics["cancelled"] != 0) throw Cancelled();
  result.metrics.erase("cancelled");
  if (c.write_fields && spec.output_dir.empty())
    result.notes.push_back("fields were requested but the caller gave no output directory: none written");
  if (!scenario.outputs.time_series) result.series.clear();
  return result;
}

const std::vector<std::string>& ibm_metric_names() {
  static const std::vector<std::string> names{
      "steps", "end_time", "cells", "ranks", "markers", "tiling_level", "slip_rms_final", "slip_max_final",
      "slip_rms_mean", "forcing_slip_rms_final", "max_divergence_final", "wall_time_ibm_s", "wall_time_fluid_s",
      "reynolds", "diameter_cells", "fields_written", "wall_time_s"};
  return names;
}

}  // namespace systole::scene
