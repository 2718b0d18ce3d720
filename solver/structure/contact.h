#pragma once
// Contact between different bodies (issue 5, Deliver 2; MODEL.md §5 "Contact") and the lockstep
// sub-cycling of several ShellModel bodies that it needs.
//
// Scheme (ours; the seed's cell-tagging rule is ContactRule::kCellAverage below): node-to-surface penalty.
// For every node i of body A and every other body B, the closest point p of B's surface (over
// the triangles of B near i, from Verlet candidate lists built on a uniform spatial hash with
// cells of d_c + skin) with barycentric weights w_j on B's triangle and distance d = |x_i - p|.
// The side of B the node is on is remembered from when the node was at d >= d_c (sign of
// (x_i - p) . n_T, recorded only when that sign is clear: a closest point inside a face, or
// |(x_i - p) . n_T| >= d / 2); inside the contact layer d < d_c the signed gap is
//   g = sigma d,  sigma = +1 on the remembered side (or no side known), -1 across it,
// and the penalty energy W = (k_i / 2) (d_c - g)^2, k_i = kappa A_i (A_i the node's stress-free
// lumped area, kappa in kPa/mm: a contact pressure per mm of penetration into the layer) gives
//   F_i = k_i (d_c - g) sigma u,  u = (x_i - p) / d,   F_{B,j} = -w_j F_i  on B's triangle nodes.
// By the envelope theorem (p is the minimiser of |x_i - q| over B's surface) these are exactly
// -grad W, so the scheme is conservative; they sum to zero (momentum) and, F_i being parallel to
// x_i - p, their torque vanishes too. A node that crossed B (g < 0) is pushed back, with a force
// that grows with the depth, not through. Both orders (A, B) and (B, A) are evaluated.
// A viscous layer (ours, ContactOptions::damping_ratio zeta > 0): inside the layer a dashpot on
// the relative velocity v_rel = v_i - sum_j w_j v_{B,j} of the node and its closest point, of
// coefficient c_i = 2 zeta sqrt(k_i mu_i), mu_i = m_i m_p / (m_i + m_p) the reduced mass of the
// node and the point (m_p = sum_j w_j m_{B,j}), so zeta is the fraction of the penalty spring's
// critical damping. With v_n = v_rel . e and e = sigma u the push's direction,
//   F_i = max(0, k_i (d_c - g) - c_i v_n) e - c_i (v_rel - v_n e):
// the normal part lessens the push but never pulls (no adhesion when the pair separates), the
// tangential part resists sliding (the film of blood between coapted leaflets, not modelled
// otherwise). Velocities are those of the substep's half kick (velocity Verlet). It dissipates;
// the forces' sum still vanishes (their torque no longer does). Without it, surfaces pressed
// together through the layer chatter: the closed aortic valve's cusps under a held 90 mmHg with
// the mass damping 0.5/ms keep nodes sliding at 0.6-1.2 m/s, at 0.004 m/s without contact and with
// zeta 0.5 (ClosedValveLoad.TheContactsViscousLayerStillsTheClosedAorticCusps); the chatter is
// along the surfaces: a normal dashpot alone
// leaves 0.3-0.6 m/s.
// The penalty's stiffness enters each node's Gershgorin row (2 k_i on i, 2 k_i w_j on B's nodes;
// with damping divided by (sqrt(1 + zeta^2) - zeta)^2, the central difference's stable-step
// factor for a damped oscillator), so the bodies' stable_step_ms() include it.
// Not detected (ours): edge-edge crossings with no node inside the other body's layer (meshes
// of similar resolution face to face do not produce them in our tests); self-contact of a body.
// Pairs that are already within d_c in the stress-free meshes (shared annulus, commissures)
// are excluded for that node and body.
#include <cstdint>
#include <memory>
#include <vector>

#include "solver/core/state_archive.h"
#include "solver/structure/shell.h"

namespace systole::structure {

// Contact rules: kPenalty (above, the default) or kCellAverage, the seed's rule (MODEL.md §5):
// space is divided into cubic cells of side d_c; after every substep the free nodes of a cell that
// holds nodes of two or more bodies all take the mass-weighted average velocity of the cell's free
// nodes (mass weights: ours, so momentum is conserved; no forces, no effect on the stable step).
enum class ContactRule { kPenalty, kCellAverage };

struct ContactOptions {
  bool enabled = true;
  ContactRule rule = ContactRule::kPenalty;
  double distance_mm = 0.5;             // d_c: thickness of the contact layer
  double stiffness_kpa_per_mm = 40;     // kappa: k_i = kappa A_i (contact pressure kappa (d_c - g))
  double damping_ratio = 0;             // zeta: the normal dashpot / the pair's critical damping (ours)
  double skin_mm = 0.25;                // Verlet skin of the candidate lists (rebuilt when any
                                        // node moved more than skin/2 since the last build)
};

// Closest point of triangle (a, b, c) to x: p = w0 a + w1 b + w2 c; interior: inside the face.
struct TrianglePoint {
  Vec3 p;
  double w[3];
  bool interior;
};
TrianglePoint closest_point_on_triangle(const Vec3& x, const Vec3& a, const Vec3& b, const Vec3& c);

struct ContactStats {
  int active = 0;              // node-surface pairs with d < d_c (g < d_c)
  int crossed = 0;             // of which g < 0 (node on the wrong side of the other surface)
  double min_gap_mm = 1e300;   // smallest g over the active pairs
  double energy_uj = 0;        // sum of the penalty energies
  long candidate_builds = 0;   // rebuilds of the candidate lists so far
  long body_rebuilds = 0;      // bodies re-hashed in those rebuilds (only those that moved; this
                               // process's count: not kept in checkpoints)
  long candidates = 0;         // node-triangle candidates in the current lists (all pairs)
  long evaluated_nodes = 0;    // nodes whose closest point was computed at the last evaluation
  int shared_cells = 0;        // kCellAverage: cells holding nodes of several bodies (last substep)
};

// Several bodies advanced in lockstep (one substep for all, the smallest stable step), with
// contact between different bodies. Owns its bodies (a copy saves and restores the whole state).
class BodyGroup {
 public:
  // Throws InputError for a non-positive distance or negative stiffness or skin, or threads
  // outside [1, 256]. threads > 1 spreads the bodies over OpenMP threads in every substep
  // (each body's own force loop then runs on one thread; the contact pass is serial).
  BodyGroup(std::vector<ShellModel> bodies, const ContactOptions& options, int threads = 1);

  std::size_t body_count() const { return bodies_.size(); }
  ShellModel& body(std::size_t k) { return bodies_[k]; }
  const ShellModel& body(std::size_t k) const { return bodies_[k]; }
  const ContactOptions& options() const { return options_; }

  // Smallest stable step of the bodies (contact stiffness included).
  double stable_step_ms() const;
  // What sets stable_step_ms(): the body and its limiting node (ShellModel::stable_step_limiter),
  // or the contact's skin / 2 per substep and the fastest node.
  std::string stable_step_limiter() const;
  // Like ShellModel::advance, for all bodies together: n = ceil(T / stable step) equal substeps,
  // re-planned when the refreshed stable step falls below the substep; loads held; the same
  // strain, step-collapse and energy-growth checks, per body.
  AdvanceStats advance(double T_ms);
  // One substep for all bodies: half kick + drift of each, contact forces at the new positions,
  // forces + half kick of each.
  void substep(double dt_ms);
  // Recomputes the contact loads at the current positions and the bodies' forces (after
  // set_state on a body, or to read the contact state of a configuration).
  void refresh_contact();

  // Checkpoints: every body's positions, velocities and clock, and the contact's memory (the
  // remembered sides, the positions of the last candidate build, the build count) under
  // `prefix`. import_state() into a group built from the same meshes and options recomputes
  // the candidates and the contact forces from them, so the group continues bitwise as the
  // exporting one would; InputError for a missing entry or another size. Held inputs (loads,
  // tension, limiter) are the caller's to set again.
  void export_state(StateArchive& archive, const std::string& prefix) const;
  void import_state(const StateArchive& archive, const std::string& prefix);

  // Contact state at the last evaluation.
  const ContactStats& contact_stats() const { return stats_; }
  // Contact forces (mN) on the nodes of body k at the last evaluation (zero when off).
  const std::vector<Vec3>& contact_forces_mn(std::size_t k) const { return force_[k]; }
  // Penalty energy of the bodies at their current positions, with the remembered sides (uJ).
  double contact_energy_uj() const { return stats_.energy_uj; }

 private:
  // The fastest node of the group: |v|^2 (mm/ms)^2, its body and node (0 when all rest).
  struct Fastest {
    double v2 = 0;
    std::size_t body = 0, node = 0;
  };
  Fastest fastest_node() const;

  struct Pair {
    std::size_t a, b;                       // nodes of a against the surface of b
    std::vector<std::int32_t> offset, tri;  // candidate triangles of b per node of a (CSR)
    std::vector<std::int8_t> side;          // remembered side (+1, -1; 0 unknown)
    std::vector<std::uint8_t> excluded;     // within d_c of b in the stress-free meshes
  };
  struct TriangleHash;
  static TriangleHash hash_triangles(const std::vector<Vec3>& x, const std::vector<geometry::Tri>& tri, double radius);
  static void build_candidates(Pair& pair, const std::vector<Vec3>& xa, const TriangleHash& hash);
  void maybe_rebuild();
  // Hashes body k's triangles at x_build_[k] (search radius d_c + skin) into hash_[k].
  void rehash_body(std::size_t k);
  void evaluate_contact();
  void average_shared_cells();  // kCellAverage

  std::vector<ShellModel> bodies_;
  ContactOptions options_;
  std::vector<Pair> pairs_;
  std::vector<std::vector<double>> area_;       // lumped stress-free node areas
  std::vector<std::vector<Vec3>> x_build_;      // per body: positions at its last candidate build
  // Per body: its triangles hashed at x_build_ (immutable once built, so copies of the group share them)
  std::vector<std::shared_ptr<const TriangleHash>> hash_;
  std::vector<std::vector<Vec3>> force_;        // contact forces per body
  std::vector<std::vector<double>> row_;        // contact stiffness rows per body
  ContactStats stats_;
  int threads_ = 1;
};

}  // namespace systole::structure
