#include "solver/structure/shell.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <omp.h>

#include "solver/core/errors.h"
#include "solver/geometry/topology.h"
#include "solver/structure/law_kernels.h"

namespace systole::structure {
namespace {

using geometry::Tissue;

std::string fmt(double v) {
  std::ostringstream o;
  o << v;
  return o.str();
}

// Signed angle between the normals of face 1 (e0, e1, o1) and face 2 (e1, e0, o2):
// theta = atan2((n2 x n1) . e_hat, n1 . n2); 0 for a flat hinge, > 0 when o1 moves along n1.
struct HingeGeometry {
  double sin_t, cos_t;  // of theta
  Vec3 grad[4];         // d theta / d (e0, e1, o1, o2) (Bridson, Marino & Fedkiw 2003, u1..u4)
  double grad_bound[4]; // upper bounds of |grad[a]| (for the stable step), no extra sqrt
};

HingeGeometry hinge_geometry(const Vec3& e0, const Vec3& e1, const Vec3& o1, const Vec3& o2) {
  const Vec3 e = e1 - e0;
  const Vec3 w1 = o1 - e0, w2 = o2 - e1;
  const Vec3 n1 = e.cross(w1);
  const Vec3 n2 = w2.cross(e);  // = (e0 - e1) x (o2 - e1)
  const double ee = e.squaredNorm();
  const double n1s = n1.squaredNorm(), n2s = n2.squaredNorm();
  const double el = std::sqrt(ee), inv_el = 1 / el;
  const double inv_n1l = 1 / std::sqrt(n1s), inv_n2l = 1 / std::sqrt(n2s);
  HingeGeometry h;
  // (n2 x n1) . e = |e|^2 n1 . (o2 - e1) (n1 is normal to e), so no second cross product.
  h.sin_t = el * n1.dot(w2) * inv_n1l * inv_n2l;
  h.cos_t = n1.dot(n2) * inv_n1l * inv_n2l;
  const Vec3 u1 = (inv_n1l * inv_n1l) * n1, u2 = (inv_n2l * inv_n2l) * n2;
  // (o1 - e1).e = w1.e - |e|^2 ; (o2 - e0).e = w2.e + |e|^2
  const double w1e = w1.dot(e), w2e = w2.dot(e);
  const double a1 = (w1e - ee) * inv_el, a2 = w2e * inv_el;
  const double b1 = w1e * inv_el, b2 = (w2e + ee) * inv_el;
  h.grad[2] = el * u1;
  h.grad[3] = el * u2;
  h.grad[0] = a1 * u1 + a2 * u2;
  h.grad[1] = -b1 * u1 - b2 * u2;
  h.grad_bound[2] = el * inv_n1l;
  h.grad_bound[3] = el * inv_n2l;
  h.grad_bound[0] = std::abs(a1) * inv_n1l + std::abs(a2) * inv_n2l;
  h.grad_bound[1] = std::abs(b1) * inv_n1l + std::abs(b2) * inv_n2l;
  return h;
}

double hinge_angle(const Vec3& e0, const Vec3& e1, const Vec3& o1, const Vec3& o2) {
  const Vec3 e = e1 - e0;
  const Vec3 n1 = e.cross(o1 - e0);
  const Vec3 n2 = (e0 - e1).cross(o2 - e1);
  return std::atan2(n2.cross(n1).dot(e) / e.norm(), n1.dot(n2));
}

// Springs: forces into f; when `row` is given, also the Gershgorin row sums of the tangent
// stiffness (axial df/dl = C/l^2 (tau' l0/l - tau) and transverse f/l, 2 max of both per end).
template <class Law>
void spring_loop(const std::vector<EdgeSpring>& springs, const std::vector<Vec3>& x, const LawParams& lp,
                 Vec3* f, double* row, double limit, double& worst, std::int32_t& worst_edge,
                 std::int32_t& bad_edge, std::int32_t k0 = 0, std::int32_t k1 = -1) {
  const std::int32_t n = k1 < 0 ? static_cast<std::int32_t>(springs.size()) : k1;
  for (std::int32_t k = k0; k < n; ++k) {
    const EdgeSpring& s = springs[k];
    const Vec3 d = x[s.j] - x[s.i];
    const double l = d.norm();
    const double eps = 1 - s.rest_length_mm / l;
    double tau, dtau;
    Law::stress_tangent(eps, s.c_kpa, s.alpha, lp, tau, dtau);
    const double c_l2 = s.cross_section_mm3 / (l * l);
    const Vec3 fv = (tau * c_l2) * d;  // on i, towards j when stretched
    f[s.i] += fv;
    f[s.j] -= fv;
    if (row) {
      const double k_axial = std::abs(c_l2 * (dtau * s.rest_length_mm / l - tau));
      const double kk = 2 * std::max(k_axial, std::abs(tau * c_l2));
      row[s.i] += kk;
      row[s.j] += kk;
    }
    const double ae = std::abs(eps);
    if (ae > worst) {
      worst = ae;
      worst_edge = k;
    }
    if (!(ae <= limit) && bad_edge < 0) bad_edge = k;
  }
}

// The edges as strain probes only (options.membrane = "triangles": the triangles carry the
// in-plane stress; the edges still report strains and trip the strain limit).
struct StrainOnly {
  static void stress_tangent(double, double, double, const LawParams&, double& tau, double& dtau) {
    tau = 0;
    dtau = 0;
  }
};

}  // namespace

ShellMaterials materials_from_config(const config::Tissue& t) {
  auto conv = [](const config::FungTissue& f) { return TissueMaterial{f.fung_c_pa * 1e-3, f.alpha_f, f.alpha_c}; };
  ShellMaterials m;
  m.tissue[static_cast<int>(Tissue::kValvularPlane)] = conv(t.lv);
  m.tissue[static_cast<int>(Tissue::kLvMyocardium)] = conv(t.lv);
  m.tissue[static_cast<int>(Tissue::kLaMyocardium)] = conv(t.la);
  m.tissue[static_cast<int>(Tissue::kMitralLeaflet)] = conv(t.mitral_leaflets);
  m.tissue[static_cast<int>(Tissue::kAorticLeaflet)] = conv(t.aortic_leaflets);
  m.tissue[static_cast<int>(Tissue::kAorticWall)] = conv(t.aorta);
  m.tissue[static_cast<int>(Tissue::kVeinOstium)] = conv(t.la);
  m.density_mg_per_mm3 = t.density_g_per_ml;  // 1 g/ml = 1 mg/mm^3
  m.poisson_ratio = t.poisson_ratio;
  return m;
}

double cavity_volume_mm3(const std::vector<Vec3>& x, const std::vector<geometry::Tri>& tri,
                         double plane_z_mm) {
  double v = 0;
  for (const auto& t : tri) {
    const Vec3& a = x[t[0]];
    const Vec3& b = x[t[1]];
    const Vec3& c = x[t[2]];
    const double nz = (b - a).cross(c - a).z();  // 2 A n_z
    const double zbar = (a.z() + b.z() + c.z()) / 3 - plane_z_mm;
    v -= zbar * nz / 2;
  }
  return v;
}

ShellModel::ShellModel(const geometry::TriMesh& stress_free, const ShellMaterials& materials,
                       const ShellOptions& options)
    : name_(stress_free.name.empty() ? "body" : stress_free.name),
      mesh_(stress_free),
      options_(options),
      law_(&find_spring_law(options.law)) {
  const std::string body = "body '" + name_ + "'";
  try {
    mesh_.check_arrays();
  } catch (const std::exception& e) {
    throw InputError(body + ": inconsistent mesh arrays: " + e.what());
  }
  if (mesh_.has_rest_shape())
    throw InputError(body + ": the mesh is built in another shape than its stress-free one (rest_position_mm "
                     "set); build the shell on geometry::rest_shape(mesh) and start it at the built positions "
                     "(scene::body_shell)");
  if (!(options.time_step_safety > 0 && options.time_step_safety <= 1))
    throw InputError(body + ": time_step_safety = " + fmt(options.time_step_safety) + " must be in (0, 1]");
  if (!(options.strain_limit > 0 && options.strain_limit < 1))
    throw InputError(body + ": strain_limit = " + fmt(options.strain_limit) + " must be in (0, 1)");
  if (!(options.active_min_fibre_stretch >= 0 && options.active_min_fibre_stretch < 1))
    throw InputError(body + ": tissue.active_min_fibre_stretch = " + fmt(options.active_min_fibre_stretch) +
                     " must be in [0, 1)");
  if (!(options.active_cross_fibre_fraction >= 0 && options.active_cross_fibre_fraction <= 1))
    throw InputError(body + ": tissue.active_cross_fibre_fraction = " + fmt(options.active_cross_fibre_fraction) +
                     " must be in [0, 1]");
  if (!(options.fung_compression_fraction >= 0 && options.fung_compression_fraction <= 1))
    throw InputError(body + ": structure.fung_compression_fraction = " + fmt(options.fung_compression_fraction) +
                     " must be in [0, 1]");
  if (!(options.fung_exponent_cap > 0))
    throw InputError(body + ": structure.fung_exponent_cap = " + fmt(options.fung_exponent_cap) + " must be > 0");
  if (options.membrane != "springs" && options.membrane != "triangles")
    throw InputError(body + ": structure.membrane = '" + options.membrane + "' is not known; known: springs, triangles");
  if (options.membrane == "triangles" && options.law != "fung")
    throw InputError(body + ": structure.membrane = 'triangles' takes the Fung law as printed (law 'fung'); got law '" +
                     options.law + "'");
  if (!(options.damping_per_ms >= 0))
    throw InputError(body + ": damping_per_ms = " + fmt(options.damping_per_ms) + " must be >= 0");
  if (options.threads < 1 || options.threads > 256)
    throw InputError(body + ": threads = " + std::to_string(options.threads) + " must be in [1, 256]");
  if (options.restep_interval < 1)
    throw InputError(body + ": restep_interval = " + std::to_string(options.restep_interval) + " must be >= 1");
  if (!(options.area_floor >= 0 && options.area_floor < 1))
    throw InputError(body + ": structure.area_floor = " + fmt(options.area_floor) + " must be in [0, 1)");
  if (!(options.area_floor_modulus_kpa > 0 && std::isfinite(options.area_floor_modulus_kpa)))
    throw InputError(body + ": structure.area_floor_modulus_kpa = " + fmt(options.area_floor_modulus_kpa) +
                     " kPa must be > 0");
  if (!(materials.density_mg_per_mm3 > 0))
    throw InputError(body + ": density = " + fmt(materials.density_mg_per_mm3) + " mg/mm^3 must be > 0");
  if (!(materials.poisson_ratio >= 0 && materials.poisson_ratio < 1))
    throw InputError(body + ": poisson_ratio = " + fmt(materials.poisson_ratio) + " must be in [0, 1)");
  const std::size_t nn = mesh_.node_count(), nt = mesh_.triangle_count();
  if (nn == 0 || nt == 0) throw InputError(body + ": empty mesh");

  // --- materials and triangles ---
  std::vector<double> area(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const double s = mesh_.thickness_mm[t];
    if (!(s > 0 && std::isfinite(s)))
      throw InputError(body + ": triangle " + std::to_string(t) + " has thickness_mm = " + fmt(s) + "; must be > 0");
    const TissueMaterial& m = materials.tissue[static_cast<int>(mesh_.tissue[t])];
    const std::string tname(geometry::tissue_name(mesh_.tissue[t]));
    if (!(m.c_kpa > 0 && std::isfinite(m.c_kpa)))
      throw InputError(body + ": tissue " + tname + " has c = " + fmt(m.c_kpa) + " kPa; must be > 0");
    if (!(m.alpha_f >= 0 && m.alpha_c >= 0 && m.alpha_f + m.alpha_c > 0))
      throw InputError(body + ": tissue " + tname + " has alpha_f = " + fmt(m.alpha_f) + ", alpha_c = " +
                       fmt(m.alpha_c) + "; must be >= 0 and not both 0");
    const auto& tr = mesh_.tri[t];
    const double lmax = std::max({(mesh_.position_mm[tr[1]] - mesh_.position_mm[tr[0]]).norm(),
                                  (mesh_.position_mm[tr[2]] - mesh_.position_mm[tr[1]]).norm(),
                                  (mesh_.position_mm[tr[0]] - mesh_.position_mm[tr[2]]).norm()});
    area[t] = mesh_.area_mm2(t);
    if (!(area[t] > 1e-10 * lmax * lmax))
      throw InputError(body + ": triangle " + std::to_string(t) + " (nodes " + std::to_string(tr[0]) + ", " +
                       std::to_string(tr[1]) + ", " + std::to_string(tr[2]) + ") has zero area");
  }
  // --- node masses (eq 15) ---
  mass_.assign(nn, 0.0);
  for (std::size_t t = 0; t < nt; ++t)
    for (int k = 0; k < 3; ++k)
      mass_[mesh_.tri[t][k]] += materials.density_mg_per_mm3 * mesh_.thickness_mm[t] * area[t] / 3;
  inv_mass_.assign(nn, 0.0);
  for (std::size_t i = 0; i < nn; ++i) inv_mass_[i] = mass_[i] > 0 ? 1 / mass_[i] : 0;

  // --- springs (eq 17-18) and hinges (eq 19) ---
  const geometry::EdgeTopology topo(mesh_);
  springs_.reserve(topo.edge_count());
  for (std::size_t e = 0; e < topo.edge_count(); ++e) {
    const auto [a, b] = topo.edge[e];
    const Vec3 d = mesh_.position_mm[b] - mesh_.position_mm[a];
    const double l0 = d.norm();
    if (!(l0 > 0))
      throw InputError(body + ": edge " + std::to_string(a) + "-" + std::to_string(b) + " has zero length");
    const Vec3 dir = d / l0;
    double cross = 0, c = 0, cos2 = 0, af = 0, ac = 0, s_mean = 0;
    const int nf = topo.face_count_of(e);
    for (int k = topo.edge_face_offset[e]; k < topo.edge_face_offset[e + 1]; ++k) {
      const int t = topo.edge_face[k];
      const TissueMaterial& m = materials.tissue[static_cast<int>(mesh_.tissue[t])];
      cross += mesh_.thickness_mm[t] * area[t];
      c += m.c_kpa / nf;
      af += m.alpha_f / nf;
      ac += m.alpha_c / nf;
      s_mean += mesh_.thickness_mm[t] / nf;
      const Vec3& fib = mesh_.fibre[t];
      const double fn = fib.norm();
      // No fibre given: an isotropic edge, cos^2 phi = 1/2 (ours).
      cos2 += (fn > 0 ? std::pow(dir.dot(fib) / fn, 2) : 0.5) / nf;
    }
    const double alpha = alpha_phi(af, ac, cos2);
    springs_.push_back({a, b, l0, cross, c, alpha});
    if (!options.bending || nf != 2) continue;
    const int f1 = topo.edge_face[topo.edge_face_offset[e]];
    const int f2 = topo.edge_face[topo.edge_face_offset[e] + 1];
    const bool fwd1 = geometry::EdgeTopology::traverses_forward(mesh_, f1, a, b);
    const bool fwd2 = geometry::EdgeTopology::traverses_forward(mesh_, f2, a, b);
    if (fwd1 == fwd2)
      throw InputError(body + ": triangles " + std::to_string(f1) + " and " + std::to_string(f2) +
                       " sharing edge " + std::to_string(a) + "-" + std::to_string(b) + " are inconsistently oriented");
    const int first = fwd1 ? f1 : f2, second = fwd1 ? f2 : f1;
    const std::int32_t e0 = fwd1 ? a : b, e1 = fwd1 ? b : a;
    auto opposite = [&](int t) {
      for (int k = 0; k < 3; ++k)
        if (mesh_.tri[t][k] != a && mesh_.tri[t][k] != b) return mesh_.tri[t][k];
      return std::int32_t{-1};
    };
    BendingHinge h;
    h.e0 = e0;
    h.e1 = e1;
    h.o1 = opposite(first);
    h.o2 = opposite(second);
    const auto& p = mesh_.position_mm;
    h.theta0 = options.flat_rest_angles ? 0.0 : hinge_angle(p[h.e0], p[h.e1], p[h.o1], p[h.o2]);
    h.cos0 = std::cos(h.theta0);
    h.sin0 = std::sin(h.theta0);
    const double nu = materials.poisson_ratio;
    const double B = c * alpha * s_mean * s_mean * s_mean / (12 * (1 - nu * nu));
    h.kb_uj = 2 * B / std::sqrt(3.0);
    hinges_.push_back(h);
  }

  // --- active triangles (eq 24, (ours) contractile form) ---
  active_.reserve(nt);
  for (std::size_t t = 0; t < nt; ++t) {
    const auto& tr = mesh_.tri[t];
    const Vec3 e1 = mesh_.position_mm[tr[1]] - mesh_.position_mm[tr[0]];
    const Vec3 e2 = mesh_.position_mm[tr[2]] - mesh_.position_mm[tr[0]];
    Vec3 f0 = mesh_.fibre[t];
    double w0 = 0, w1 = 0, v0 = 0, v1 = 0;
    if (f0.norm() > 0) {
      const Vec3 n = e1.cross(e2).normalized();
      f0 = (f0 - f0.dot(n) * n).normalized();  // tangent, unit
      const Vec3 c0 = n.cross(f0);              // the cross-fibre direction in the plane
      const double g11 = e1.dot(e1), g12 = e1.dot(e2), g22 = e2.dot(e2);
      const double det = g11 * g22 - g12 * g12;
      const double r1 = e1.dot(f0), r2 = e2.dot(f0);
      w0 = (g22 * r1 - g12 * r2) / det;
      w1 = (g11 * r2 - g12 * r1) / det;
      const double q1 = e1.dot(c0), q2 = e2.dot(c0);
      v0 = (g22 * q1 - g12 * q2) / det;
      v1 = (g11 * q2 - g12 * q1) / det;
    }
    active_.push_back({tr[0], tr[1], tr[2], w0, w1, v0, v1, mesh_.thickness_mm[t] * area[t]});
  }
  active_tension_kpa_.assign(nn, 0.0);
  if (options.membrane == "triangles") build_membrane(materials);
  if (options.area_floor > 0) {
    floor_area_mm2_ = area;
    floor_kappa_s_.resize(nt);
    for (std::size_t t = 0; t < nt; ++t) floor_kappa_s_[t] = options.area_floor_modulus_kpa * mesh_.thickness_mm[t];
  }

  // --- state ---
  fixed_.assign(nn, 0);
  if (options.anchor_tagged_nodes)
    for (std::size_t i = 0; i < nn; ++i) fixed_[i] = (mesh_.region[i] & geometry::kAnchor) ? 1 : 0;
  x_ = mesh_.position_mm;
  v_.assign(nn, Vec3::Zero());
  external_.assign(nn, Vec3::Zero());
  force_.assign(nn, Vec3::Zero());
  fixed_target_ = x_;
  compute_forces();
}

void ShellModel::set_external_loads(std::vector<Vec3> force_mn) {
  if (force_mn.size() != node_count())
    throw std::invalid_argument("set_external_loads: " + std::to_string(force_mn.size()) + " loads for " +
                                std::to_string(node_count()) + " nodes of body '" + name_ + "'");
  external_ = std::move(force_mn);
  compute_forces();
}

void ShellModel::set_rest_lengths_mm(const std::vector<double>& rest_length_mm) {
  if (rest_length_mm.size() != springs_.size())
    throw std::invalid_argument("set_rest_lengths_mm: " + std::to_string(rest_length_mm.size()) + " lengths for " +
                                std::to_string(springs_.size()) + " springs of body '" + name_ + "'");
  for (std::size_t k = 0; k < springs_.size(); ++k)
    if (!(rest_length_mm[k] > 0 && std::isfinite(rest_length_mm[k])))
      throw InputError(name_ + ": rest length " + fmt(rest_length_mm[k]) + " mm of spring " + std::to_string(springs_[k].i) +
                       "-" + std::to_string(springs_[k].j) + " must be finite and > 0");
  for (std::size_t k = 0; k < springs_.size(); ++k) springs_[k].rest_length_mm = rest_length_mm[k];
  compute_forces();
}

void ShellModel::set_cavity_pressure(double pressure_kpa) {
  pressure_kpa_ = pressure_kpa;
  compute_forces();
}

void ShellModel::set_active_tension(std::vector<double> tension_kpa) {
  if (tension_kpa.size() != node_count())
    throw std::invalid_argument("set_active_tension: wrong size for body '" + name_ + "'");
  active_tension_kpa_ = std::move(tension_kpa);
  active_on_ = std::any_of(active_tension_kpa_.begin(), active_tension_kpa_.end(), [](double v) { return v != 0; });
  compute_forces();
}

void ShellModel::fix_nodes(const std::vector<std::int32_t>& nodes) {
  for (auto i : nodes) {
    fixed_.at(i) = 1;
    v_[i].setZero();
    fixed_target_[i] = x_[i];
  }
  compute_forces();
}

void ShellModel::move_fixed_nodes(const Eigen::Matrix3d& rotation, const Vec3& translation_mm) {
  for (std::size_t i = 0; i < node_count(); ++i)
    if (fixed_[i]) fixed_target_[i] = rotation * mesh_.position_mm[i] + translation_mm;
}

void ShellModel::set_displacement_limit(const Vec3& axis, double max_mm) {
  set_displacement_limit(axis, max_mm, mesh_.position_mm);
}

void ShellModel::set_displacement_limit(const Vec3& axis, double max_mm, std::vector<Vec3> reference_mm) {
  if (!(axis.norm() > 0) || !(max_mm >= 0))
    throw InputError("body '" + name_ + "': displacement limit needs a non-zero axis and max_mm >= 0");
  if (reference_mm.size() != node_count())
    throw InputError("body '" + name_ + "': the displacement limit's reference has " +
                     std::to_string(reference_mm.size()) + " positions, the body " + std::to_string(node_count()) +
                     " nodes");
  limit_on_ = true;
  limit_axis_ = axis.normalized();
  limit_mm_ = max_mm;
  limit_reference_mm_ = std::move(reference_mm);
}

void ShellModel::set_radial_limit(const Vec3& axis_point_mm, const Vec3& axis_direction, double radius_mm) {
  if (!(axis_direction.norm() > 0) || !(radius_mm > 0) || !std::isfinite(radius_mm))
    throw InputError("body '" + name_ + "': radial limit needs a non-zero axis and a radius > 0 (got " +
                     std::to_string(radius_mm) + " mm)");
  radial_on_ = true;
  radial_point_mm_ = axis_point_mm;
  radial_axis_ = axis_direction.normalized();
  radial_max_mm_.resize(node_count());
  for (std::size_t i = 0; i < node_count(); ++i) {
    const Vec3 d = mesh_.position_mm[i] - radial_point_mm_;
    radial_max_mm_[i] = std::max(radius_mm, (d - d.dot(radial_axis_) * radial_axis_).norm());
  }
}

void ShellModel::set_state(std::vector<Vec3> x_mm, std::vector<Vec3> v_mm_per_ms) {
  if (x_mm.size() != node_count() || v_mm_per_ms.size() != node_count())
    throw std::invalid_argument("set_state: wrong size for body '" + name_ + "'");
  x_ = std::move(x_mm);
  v_ = std::move(v_mm_per_ms);
  for (std::size_t i = 0; i < node_count(); ++i)
    if (fixed_[i]) fixed_target_[i] = x_[i];
  compute_forces();
}

// ---------------------------------------------------------------------------------------------
// Force kernels
void ShellModel::add_spring_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const {
  if (!membrane_.empty()) return;  // the edges are strain probes only
  double worst = 0;
  std::int32_t we = -1, bad = -1;
  const double inf = std::numeric_limits<double>::infinity();
  const LawParams q{options_.fung_exponent_cap, options_.fung_compression_fraction};
  switch (law_->kind) {
    case LawKind::kFung: spring_loop<kernels::Fung>(springs_, x, q, f.data(), nullptr, inf, worst, we, bad); break;
    case LawKind::kLinear: spring_loop<kernels::Linear>(springs_, x, q, f.data(), nullptr, inf, worst, we, bad); break;
    case LawKind::kNeoHookean:
      spring_loop<kernels::NeoHookean>(springs_, x, q, f.data(), nullptr, inf, worst, we, bad);
      break;
    case LawKind::kFungTension:
      spring_loop<kernels::FungTension>(springs_, x, q, f.data(), nullptr, inf, worst, we, bad);
      break;
  }
}

double ShellModel::spring_energy(const std::vector<Vec3>& x) const {
  double w = 0;
  if (!membrane_.empty()) return w;
  for (const EdgeSpring& s : springs_) {
    const double l = (x[s.j] - x[s.i]).norm();
    w += edge_energy(*law_, 1 - s.rest_length_mm / l, s.c_kpa, s.alpha, LawParams{options_.fung_exponent_cap, options_.fung_compression_fraction}, s.cross_section_mm3);
  }
  return w;
}

void ShellModel::add_bending_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const {
  for (const BendingHinge& h : hinges_) {
    const HingeGeometry g = hinge_geometry(x[h.e0], x[h.e1], x[h.o1], x[h.o2]);
    const double m = -h.kb_uj * (g.sin_t * h.cos0 - g.cos_t * h.sin0);  // -dW/dtheta = -k_b sin(theta - theta0)
    f[h.e0] += m * g.grad[0];
    f[h.e1] += m * g.grad[1];
    f[h.o1] += m * g.grad[2];
    f[h.o2] += m * g.grad[3];
  }
}

double ShellModel::bending_energy(const std::vector<Vec3>& x) const {
  double w = 0;
  for (const BendingHinge& h : hinges_)
    w += h.kb_uj * (1 - std::cos(hinge_angle(x[h.e0], x[h.e1], x[h.o1], x[h.o2]) - h.theta0));
  return w;
}

// The area floor (ours; header): W = kappa s A0 (J0 - J)^2 / J below J0, dW/dJ = -kappa s A0
// (J0^2/J^2 - 1), so the force is pi dA/dx with pi = kappa s (J0^2/J^2 - 1) (mN/mm) and
// dA/dx_a = n x (x_c - x_b) / 2 (cyclic). Gershgorin rows (row != nullptr): the J-curvature
// term kappa s 2 J0^2 / (J^3 A0) |g_a| sum_b |g_b| plus |pi| times a bound on the area's
// Hessian blocks, 3 (l_max^2 / (4 A) + 1/2) (an out-of-plane motion of a node changes A at
// second order as l^2 / (4 A); ours, approximate as the hinges' bound).
void ShellModel::add_area_floor_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f, double* row) const {
  if (floor_area_mm2_.empty()) return;
  const double j0 = options_.area_floor;
  for (std::size_t t = 0; t < mesh_.tri.size(); ++t) {
    const auto& tr = mesh_.tri[t];
    const Vec3 &xa = x[tr[0]], &xb = x[tr[1]], &xc = x[tr[2]];
    const Vec3 n2 = (xb - xa).cross(xc - xa);
    const double twice_area = n2.norm();
    const double a0 = floor_area_mm2_[t], j = 0.5 * twice_area / a0;
    if (j >= j0 || !(twice_area > 0)) continue;
    const Vec3 n = n2 / twice_area;
    const Vec3 g[3] = {0.5 * n.cross(xc - xb), 0.5 * n.cross(xa - xc), 0.5 * n.cross(xb - xa)};
    const double ks = floor_kappa_s_[t];
    const double pi = ks * (j0 * j0 / (j * j) - 1);
    for (int k = 0; k < 3; ++k) f[tr[k]] += pi * g[k];
    if (row == nullptr) continue;
    const double gn[3] = {g[0].norm(), g[1].norm(), g[2].norm()};
    const double lmax2 = std::max({(xb - xa).squaredNorm(), (xc - xb).squaredNorm(), (xa - xc).squaredNorm()});
    const double curv = ks * 2 * j0 * j0 / (j * j * j * a0) * (gn[0] + gn[1] + gn[2]);
    const double geo = pi * 3 * (lmax2 / (2 * twice_area) + 0.5);
    for (int k = 0; k < 3; ++k) row[tr[k]] += curv * gn[k] + geo;
  }
}

double ShellModel::area_floor_energy(const std::vector<Vec3>& x) const {
  if (floor_area_mm2_.empty()) return 0;
  const double j0 = options_.area_floor;
  double w = 0;
  for (std::size_t t = 0; t < mesh_.tri.size(); ++t) {
    const auto& tr = mesh_.tri[t];
    const double a0 = floor_area_mm2_[t];
    const double j = 0.5 * (x[tr[1]] - x[tr[0]]).cross(x[tr[2]] - x[tr[0]]).norm() / a0;
    if (j < j0) w += floor_kappa_s_[t] * a0 * (j0 - j) * (j0 - j) / j;
  }
  return w;
}

namespace {
// Length–tension relation of the active stress (ours, options.active_min_fibre_stretch = m > 0):
// the tension is tau f(lambda) with f = 1 for lambda >= 1, f = 1 - ((1 - lambda)/(1 - m))^2 on
// [m, 1] and f = 0 below m; g is its primitive with g(1) = 1, so W_act = tau s A g(lambda).
// m = 0: f = 1, g = lambda (eq 24 as in the seed, no length dependence).
struct LengthTension {
  double f, df, g;
};
LengthTension length_tension(double lambda, double m) {
  if (m <= 0 || lambda >= 1) return {1, 0, lambda};
  const double d = 1 - m;
  if (lambda <= m) return {0, 0, m + d / 3};
  const double r = (1 - lambda) / d;
  return {1 - r * r, 2 * r / d, lambda + (1 - lambda) * r * r / 3};
}
}  // namespace

void ShellModel::add_active_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const {
  if (!active_on_) return;
  const double kc = options_.active_cross_fibre_fraction;
  // one direction d0 = w0 (X_b - X_a) + w1 (X_c - X_a) with weight k: W = k tau s A g(|F d0|)
  auto add = [&](const ActiveTriangle& t, double w0, double w1, double k_tau) {
    const Vec3 ff = w0 * (x[t.b] - x[t.a]) + w1 * (x[t.c] - x[t.a]);  // F d0
    const double lam = ff.norm();
    const double fl = length_tension(lam, options_.active_min_fibre_stretch).f;
    const Vec3 u = (k_tau * fl * t.volume_mm3 / lam) * ff;  // dW/d(F d0)
    f[t.b] -= w0 * u;
    f[t.c] -= w1 * u;
    f[t.a] += (w0 + w1) * u;
  };
  for (const ActiveTriangle& t : active_) {
    const double tau = (active_tension_kpa_[t.a] + active_tension_kpa_[t.b] + active_tension_kpa_[t.c]) / 3;
    if (tau == 0 || (t.w0 == 0 && t.w1 == 0)) continue;
    add(t, t.w0, t.w1, tau);
    if (kc > 0) add(t, t.v0, t.v1, kc * tau);
  }
}

double ShellModel::active_energy(const std::vector<Vec3>& x) const {
  double w = 0;
  const double m = options_.active_min_fibre_stretch, kc = options_.active_cross_fibre_fraction;
  for (const ActiveTriangle& t : active_) {
    const double tau = (active_tension_kpa_[t.a] + active_tension_kpa_[t.b] + active_tension_kpa_[t.c]) / 3;
    if (tau == 0 || (t.w0 == 0 && t.w1 == 0)) continue;
    const double lam = (t.w0 * (x[t.b] - x[t.a]) + t.w1 * (x[t.c] - x[t.a])).norm();
    w += tau * t.volume_mm3 * length_tension(lam, m).g;
    if (kc > 0) {
      const double lc = (t.v0 * (x[t.b] - x[t.a]) + t.v1 * (x[t.c] - x[t.a])).norm();
      w += kc * tau * t.volume_mm3 * length_tension(lc, m).g;
    }
  }
  return w;
}

void ShellModel::add_pressure_forces(const std::vector<Vec3>& x, std::vector<Vec3>& f) const {
  if (pressure_kpa_ == 0) return;
  const double k = -pressure_kpa_ / 6;  // -p (2 A n) / 6 = -p A n / 3 per node
  for (const auto& t : mesh_.tri) {
    const Vec3 n2a = (x[t[1]] - x[t[0]]).cross(x[t[2]] - x[t[0]]);
    const Vec3 fv = k * n2a;
    f[t[0]] += fv;
    f[t[1]] += fv;
    f[t[2]] += fv;
  }
}

double ShellModel::pressure_volume(const std::vector<Vec3>& x) const {
  return structure::cavity_volume_mm3(x, mesh_.tri, options_.cavity_plane_z_mm);
}

// Springs and hinges of the ranges [s0, s1) and [h0, h1) into f and row (one thread's share).
void ShellModel::internal_forces_range(Vec3* f, double* row, std::int32_t s0, std::int32_t s1, std::int32_t h0,
                                       std::int32_t h1, double& worst, std::int32_t& worst_edge,
                                       std::int32_t& bad) const {
  const double lim = options_.strain_limit;
  const LawParams q{options_.fung_exponent_cap, options_.fung_compression_fraction};
  if (!membrane_.empty()) spring_loop<StrainOnly>(springs_, x_, q, f, row, lim, worst, worst_edge, bad, s0, s1);
  else switch (law_->kind) {
    case LawKind::kFung: spring_loop<kernels::Fung>(springs_, x_, q, f, row, lim, worst, worst_edge, bad, s0, s1); break;
    case LawKind::kLinear:
      spring_loop<kernels::Linear>(springs_, x_, q, f, row, lim, worst, worst_edge, bad, s0, s1);
      break;
    case LawKind::kNeoHookean:
      spring_loop<kernels::NeoHookean>(springs_, x_, q, f, row, lim, worst, worst_edge, bad, s0, s1);
      break;
    case LawKind::kFungTension:
      spring_loop<kernels::FungTension>(springs_, x_, q, f, row, lim, worst, worst_edge, bad, s0, s1);
      break;
  }
  // Bending, with the hinges' Gershgorin rows: k_b (|cos| + |sin|)(theta - theta0) |g_a| sum_b |g_b|
  // (the sin term stands in for the curvature of theta, ours).
  for (std::int32_t k = h0; k < h1; ++k) {
    const BendingHinge& h = hinges_[k];
    const HingeGeometry g = hinge_geometry(x_[h.e0], x_[h.e1], x_[h.o1], x_[h.o2]);
    const double sin_d = g.sin_t * h.cos0 - g.cos_t * h.sin0, cos_d = g.cos_t * h.cos0 + g.sin_t * h.sin0;
    const double m = -h.kb_uj * sin_d;
    const std::int32_t nodes[4] = {h.e0, h.e1, h.o1, h.o2};
    double gs[4], sum = 0;
    for (int a = 0; a < 4; ++a) {
      f[nodes[a]] += m * g.grad[a];
      sum += (gs[a] = g.grad_bound[a]);
    }
    const double kk = h.kb_uj * (std::abs(cos_d) + std::abs(sin_d)) * sum;
    for (int a = 0; a < 4; ++a) row[nodes[a]] += kk * gs[a];
  }
}

void ShellModel::compute_forces() {
  const std::size_t nn = node_count();
  for (std::size_t i = 0; i < nn; ++i) force_[i] = external_[i];
  row_.assign(nn, 0.0);
  worst_strain_ = 0;
  worst_edge_ = -1;
  std::int32_t bad = -1;
  double* row = row_.data();
  const auto ns = static_cast<std::int32_t>(springs_.size()), nh = static_cast<std::int32_t>(hinges_.size());
  const int nt = options_.threads;
  if (nt <= 1) {
    internal_forces_range(force_.data(), row, 0, ns, 0, nh, worst_strain_, worst_edge_, bad);
  } else {
    // Per-thread buffers (thread 0 writes force_/row_ directly), then a parallel reduction over
    // nodes: no atomics, no races. Sums differ from one thread's at round-off only.
    thread_force_.resize(nt - 1);
    thread_row_.resize(nt - 1);
#pragma omp parallel num_threads(nt)
    {
      const int t = omp_get_thread_num();
      Vec3* f = force_.data();
      double* r = row;
      if (t > 0) {
        thread_force_[t - 1].assign(nn, Vec3::Zero());
        thread_row_[t - 1].assign(nn, 0.0);
        f = thread_force_[t - 1].data();
        r = thread_row_[t - 1].data();
      }
      double worst = 0;
      std::int32_t we = -1, b = -1;
      internal_forces_range(f, r, static_cast<std::int32_t>(std::int64_t{ns} * t / nt),
                            static_cast<std::int32_t>(std::int64_t{ns} * (t + 1) / nt),
                            static_cast<std::int32_t>(std::int64_t{nh} * t / nt),
                            static_cast<std::int32_t>(std::int64_t{nh} * (t + 1) / nt), worst, we, b);
#pragma omp critical(systole_structure_worst)
      {
        if (worst > worst_strain_) {
          worst_strain_ = worst;
          worst_edge_ = we;
        }
        if (b >= 0 && (bad < 0 || b < bad)) bad = b;
      }
#pragma omp barrier
#pragma omp for schedule(static)
      for (std::int64_t i = 0; i < static_cast<std::int64_t>(nn); ++i)
        for (int k = 0; k < nt - 1; ++k) {
          force_[i] += thread_force_[k][i];
          row[i] += thread_row_[k][i];
        }
    }
  }
  if (bad >= 0) {
    worst_edge_ = bad;
    worst_strain_ = std::numeric_limits<double>::quiet_NaN();  // flags the violation
  }
  if (active_on_) {
    add_active_forces(x_, force_);
    for (const ActiveTriangle& t : active_) {
      const double tau = (active_tension_kpa_[t.a] + active_tension_kpa_[t.b] + active_tension_kpa_[t.c]) / 3;
      if (tau == 0 || (t.w0 == 0 && t.w1 == 0)) continue;  // no fibre: no active force (as in add_active_forces)
      const double lam = (t.w0 * (x_[t.b] - x_[t.a]) + t.w1 * (x_[t.c] - x_[t.a])).norm();
      const LengthTension lt = length_tension(lam, options_.active_min_fibre_stretch);
      // transverse tau f / lambda and axial tau f' (the length-tension slope)
      const double k = std::abs(tau) * t.volume_mm3 * std::max(lt.f / lam, lt.df);
      const double w[3] = {std::abs(t.w0 + t.w1), std::abs(t.w0), std::abs(t.w1)};
      const double sum = w[0] + w[1] + w[2];
      row[t.a] += k * w[0] * sum;
      row[t.b] += k * w[1] * sum;
      row[t.c] += k * w[2] * sum;
      if (options_.active_cross_fibre_fraction > 0) {
        const double lc = (t.v0 * (x_[t.b] - x_[t.a]) + t.v1 * (x_[t.c] - x_[t.a])).norm();
        const LengthTension ltc = length_tension(lc, options_.active_min_fibre_stretch);
        const double kc = options_.active_cross_fibre_fraction * std::abs(tau) * t.volume_mm3 *
                          std::max(ltc.f / lc, ltc.df);
        const double v[3] = {std::abs(t.v0 + t.v1), std::abs(t.v0), std::abs(t.v1)};
        const double vs = v[0] + v[1] + v[2];
        row[t.a] += kc * v[0] * vs;
        row[t.b] += kc * v[1] * vs;
        row[t.c] += kc * v[2] * vs;
      }
    }
  }
  add_area_floor_forces(x_, force_, row);
  add_membrane_forces(x_, force_, row);
  add_pressure_forces(x_, force_);
  if (!contact_force_.empty())
    for (std::size_t i = 0; i < nn; ++i) {
      force_[i] += contact_force_[i];
      row[i] += contact_row_[i];
    }
  omega2_ = 0;
  for (std::size_t i = 0; i < nn; ++i)
    if (!fixed_[i]) omega2_ = std::max(omega2_, row[i] * inv_mass_[i]);
}

// ---------------------------------------------------------------------------------------------
// Integrator
double ShellModel::stable_step_ms() const {
  if (!(omega2_ > 0)) return std::numeric_limits<double>::infinity();
  return options_.time_step_safety * 2 / std::sqrt(omega2_);
}

std::string ShellModel::stable_step_limiter() const {
  std::size_t worst = 0;
  double w = -1;
  for (std::size_t i = 0; i < x_.size(); ++i)
    if (!fixed_[i] && row_[i] * inv_mass_[i] > w) {
      w = row_[i] * inv_mass_[i];
      worst = i;
    }
  std::ostringstream m;
  m << "node " << worst << " at (" << x_[worst].x() << ", " << x_[worst].y() << ", " << x_[worst].z()
    << ") mm, row/mass " << w << " /ms^2";
  if (worst_edge_ >= 0)
    m << "; worst edge " << springs_[worst_edge_].i << "-" << springs_[worst_edge_].j << " strain " << worst_strain_;
  // The flattest triangle at that node (ours): a triangle squeezed flat in its plane (its
  // smallest height far below the stress-free one) while its edges stay within the strain limit
  // makes the bending hinges across its edges stiffen as 1/height; name it when it is at less
  // than half its stress-free height.
  double flattest = 1e300;
  std::size_t flat_t = 0;
  auto min_height = [](const Vec3& a, const Vec3& b, const Vec3& c) {
    const double twice_area = (b - a).cross(c - a).norm();
    return twice_area / std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
  };
  for (std::size_t t = 0; t < mesh_.tri.size(); ++t) {
    const auto& tr = mesh_.tri[t];
    if (tr[0] != static_cast<int>(worst) && tr[1] != static_cast<int>(worst) && tr[2] != static_cast<int>(worst)) continue;
    const double h0 = min_height(mesh_.position_mm[tr[0]], mesh_.position_mm[tr[1]], mesh_.position_mm[tr[2]]);
    const double ratio = min_height(x_[tr[0]], x_[tr[1]], x_[tr[2]]) / h0;
    if (ratio < flattest) {
      flattest = ratio;
      flat_t = t;
    }
  }
  if (flattest < 0.5) {
    const auto& tr = mesh_.tri[flat_t];
    m << "; triangle " << flat_t << " (nodes " << tr[0] << ", " << tr[1] << ", " << tr[2] << ") squeezed flat to "
      << flattest << " of its stress-free height (an in-plane collapse)";
  }
  return m.str();
}

void ShellModel::substep(double dt) {
  begin_substep(dt);
  end_substep(dt);
}

void ShellModel::begin_substep(double dt) {
  const double h = 0.5 * dt;
  const double damp_in = 1 - options_.damping_per_ms * h;
  const std::size_t n = node_count();
  for (std::size_t i = 0; i < n; ++i) {
    if (!fixed_[i]) v_[i] = damp_in * v_[i] + (h * inv_mass_[i]) * force_[i];
    x_[i] += dt * v_[i];
  }
  if (limit_on_) {
    for (std::size_t i = 0; i < n; ++i) {
      if (fixed_[i]) continue;
      const double d = (x_[i] - limit_reference_mm_[i]).dot(limit_axis_);
      if (d <= limit_mm_) continue;
      x_[i] -= (d - limit_mm_) * limit_axis_;
      const double vn = v_[i].dot(limit_axis_);
      if (vn > 0) v_[i] -= vn * limit_axis_;
    }
  }
  if (radial_on_) {
    for (std::size_t i = 0; i < n; ++i) {
      if (fixed_[i]) continue;
      const Vec3 d = x_[i] - radial_point_mm_;
      const Vec3 radial = d - d.dot(radial_axis_) * radial_axis_;
      const double r = radial.norm();
      if (r <= radial_max_mm_[i]) continue;
      const Vec3 e = radial / r;
      x_[i] -= (r - radial_max_mm_[i]) * e;
      const double vr = v_[i].dot(e);
      if (vr > 0) v_[i] -= vr * e;
    }
  }
  time_ms_ += dt;
}

void ShellModel::end_substep(double dt) {
  const double h = 0.5 * dt;
  const double damp_out = 1 / (1 + options_.damping_per_ms * h);
  const std::size_t n = node_count();
  compute_forces();
  for (std::size_t i = 0; i < n; ++i)
    if (!fixed_[i]) v_[i] = damp_out * (v_[i] + (h * inv_mass_[i]) * force_[i]);
  if (!(worst_strain_ <= options_.strain_limit)) {
    const EdgeSpring& s = springs_[worst_edge_];
    const double l = (x_[s.j] - x_[s.i]).norm();
    std::ostringstream what;
    what << "edge " << s.i << "-" << s.j << " strain (l - l0)/l = " << (1 - s.rest_length_mm / l)
         << " (l = " << l << " mm, l0 = " << s.rest_length_mm << " mm) is beyond the strain limit "
         << options_.strain_limit << " or not finite; substep dt = " << dt << " ms";
    throw_instability(s.i, what.str());
  }
}

void ShellModel::set_contact_loads(std::vector<Vec3> force_mn, std::vector<double> stiffness_mn_per_mm) {
  if ((!force_mn.empty() && force_mn.size() != node_count()) || stiffness_mn_per_mm.size() != force_mn.size())
    throw std::invalid_argument("set_contact_loads: wrong size for body '" + name_ + "'");
  contact_force_ = std::move(force_mn);
  contact_row_ = std::move(stiffness_mn_per_mm);
}

void ShellModel::begin_advance(double T_ms) {
  // Fixed nodes move to their targets at constant velocity over T.
  moving_fixed_ = false;
  for (std::size_t i = 0; i < node_count(); ++i) {
    if (!fixed_[i]) continue;
    v_[i] = (fixed_target_[i] - x_[i]) / T_ms;
    moving_fixed_ = moving_fixed_ || v_[i].squaredNorm() > 0;
  }
}

void ShellModel::end_advance(double t_end_ms) {
  time_ms_ = t_end_ms;
  if (moving_fixed_)
    for (std::size_t i = 0; i < node_count(); ++i)
      if (fixed_[i]) {
        x_[i] = fixed_target_[i];
        v_[i].setZero();
      }
  moving_fixed_ = false;
}

void ShellModel::check_min_step() const {
  const double dt_stable = stable_step_ms();
  if (dt_stable >= options_.min_step_ms) return;
  std::ostringstream what;
  what << "the stable step collapsed to " << dt_stable << " ms (< min_step_ms " << options_.min_step_ms
       << "); largest edge strain " << worst_strain_ << "; the step is set by " << stable_step_limiter();
  throw_instability(worst_edge_ >= 0 ? springs_[worst_edge_].i : 0, what.str());
}

double ShellModel::kinetic_energy_uj() const {
  double ke = 0;
  for (std::size_t i = 0; i < node_count(); ++i) ke += 0.5 * mass_[i] * v_[i].squaredNorm();
  return ke;
}

void ShellModel::check_energy_growth(EnergyWatch& watch, double dt, double dt_stable) const {
  const double ke = kinetic_energy_uj();
  const bool grew = watch.kinetic_uj > 0 && ke > 1e3 * watch.kinetic_uj;
  if (grew && watch.grew) {
    const double pot = spring_energy(x_) + area_floor_energy(x_) + membrane_energy(x_) + bending_energy(x_);
    if (ke > pot) {
      std::size_t worst = 0;
      for (std::size_t i = 1; i < node_count(); ++i)
        if (v_[i].squaredNorm() > v_[worst].squaredNorm()) worst = i;
      std::ostringstream what;
      what << "kinetic energy grew from " << watch.kinetic_uj << " to " << ke << " uJ in " << options_.restep_interval
           << " substeps of " << dt << " ms, after growing > 1e3 times over the interval before (stable step estimate "
           << dt_stable << " ms)";
      throw_instability(static_cast<std::int32_t>(worst), what.str());
    }
  }
  watch.kinetic_uj = ke;
  watch.grew = grew;
}

std::vector<double> ShellModel::node_areas_mm2() const {
  std::vector<double> a(node_count(), 0.0);
  for (std::size_t t = 0; t < mesh_.triangle_count(); ++t)
    for (int k = 0; k < 3; ++k) a[mesh_.tri[t][k]] += mesh_.area_mm2(t) / 3;
  return a;
}

void ShellModel::throw_instability(std::int32_t node, const std::string& what) const {
  std::ostringstream place;
  place << "body '" << name_ << "' node " << node << " (stress-free position " << mesh_.position_mm[node].transpose()
        << " mm)";
  throw InstabilityError("structure", place.str(), time_ms_ * 1e-3, what);
}

AdvanceStats ShellModel::advance(double T_ms) {
  AdvanceStats stats;
  if (!(T_ms > 0)) return stats;
  const double t_end = time_ms_ + T_ms;
  begin_advance(T_ms);
  double remaining = T_ms;
  double dt_stable = stable_step_ms();
  long n = std::max(1L, static_cast<long>(std::ceil(remaining / dt_stable)));
  double dt = remaining / n;
  stats.smallest_dt_ms = dt;
  stats.largest_dt_ms = dt;
  EnergyWatch watch{kinetic_energy_uj(), false};
  int since = 0;
  while (n > 0) {
    substep(dt);
    remaining -= dt;
    --n;
    ++stats.substeps;
    if (n == 0) break;
    // The bound is refreshed by every force evaluation: re-plan the rest of the outer step as
    // soon as the current substep exceeds it (the Fung law stiffens).
    dt_stable = stable_step_ms();
    check_min_step();
    if (dt > dt_stable) {
      n = std::max(1L, static_cast<long>(std::ceil(remaining / dt_stable)));
      dt = remaining / n;
      stats.smallest_dt_ms = std::min(stats.smallest_dt_ms, dt);
    }
    if (++since < options_.restep_interval) continue;
    since = 0;
    check_energy_growth(watch, dt, dt_stable);
  }
  end_advance(t_end);
  return stats;
}

// ---------------------------------------------------------------------------------------------
// Diagnostics
Energies ShellModel::energies() const {
  Energies e;
  for (std::size_t i = 0; i < node_count(); ++i) e.kinetic_uj += 0.5 * mass_[i] * v_[i].squaredNorm();
  e.elastic_uj = spring_energy(x_) + area_floor_energy(x_) + membrane_energy(x_);
  e.bending_uj = bending_energy(x_);
  e.active_uj = active_energy(x_);
  double lp = 0;
  if (pressure_kpa_ != 0) lp -= pressure_kpa_ * pressure_volume(x_);
  for (std::size_t i = 0; i < node_count(); ++i) lp -= external_[i].dot(x_[i]);
  e.load_potential_uj = lp;
  return e;
}

std::vector<double> ShellModel::edge_strains() const {
  std::vector<double> eps(springs_.size());
  for (std::size_t k = 0; k < springs_.size(); ++k)
    eps[k] = 1 - springs_[k].rest_length_mm / (x_[springs_[k].j] - x_[springs_[k].i]).norm();
  return eps;
}

double ShellModel::max_abs_strain() const {
  double m = 0;
  for (double e : edge_strains()) m = std::max(m, std::abs(e));
  return m;
}

double ShellModel::cavity_volume_mm3() const { return pressure_volume(x_); }

}  // namespace systole::structure
