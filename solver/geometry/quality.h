#pragma once
// Mesh quality checks with clear errors, and a triangle-quality report.
//
// Each check returns issues; an issue names the check, the body and the problem, with a
// node/triangle index and position so it can be found in ParaView. All checks are
// O(n log n) (sorting) or O(n) on a uniform-grid broad phase (intersections, clearance).
#include <string>
#include <vector>

#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

struct QualityIssue {
  std::string check;    // "non_manifold_edge", "inconsistent_orientation", "hole", ...
  std::string body;
  std::string message;  // complete sentence naming the body, the problem and where
};

struct CheckOptions {
  double plane_z_mm = 0;        // the valvular plane (anchors and chamber openings lie in it)
  double plane_tolerance_mm = 1e-6;
  // Anchors tagged aortic_annulus may also lie up to this height above the plane (towards -z):
  // the crown-shaped attachment of the aortic cusps and the root wall below it (ours).
  double aortic_crown_height_mm = 0;
  double degenerate_min_angle_deg = 0.5;  // below this a triangle counts as degenerate
};

// Per-body checks: array consistency, finite positions, non-manifold edges, inconsistent
// orientation, degenerate triangles, inverted (folded) triangles, holes (a chamber's open
// loops must lie in the valvular plane; a vessel needs one there), chamber normals pointing
// into the cavity, fibres (unit, tangent), thickness > 0, and tags (unknown bits, anchors off
// the plane, a region on a tissue it does not belong to, a deformable body with no anchor).
std::vector<QualityIssue> check_body(const TriMesh& mesh, const CheckOptions& options);

// Intersections within and between bodies: triangles whose interiors cross. Triangles that
// share a node (same body) or a node position (bodies attached along a ring) are not
// compared. Broad phase: uniform grid of triangle bounding boxes.
std::vector<QualityIssue> check_intersections(const std::vector<const TriMesh*>& bodies);

// Smallest distance (mm) from a node of `a` to a triangle of `b` and vice versa, searched up
// to `search_mm` (returns search_mm if nothing is closer). Nodes and triangles tagged kAnchor
// or lying within `ignore_near_plane_mm` of the plane are ignored when that is > 0.
double min_gap_mm(const TriMesh& a, const TriMesh& b, double search_mm, double plane_z_mm = 0,
                  double ignore_near_plane_mm = -1);

struct QualityReport {
  std::size_t nodes = 0, triangles = 0, edges = 0;
  double min_angle_deg = 0, max_angle_deg = 0;
  double max_aspect_ratio = 0;   // longest edge / (2 sqrt(3) inradius): 1 for equilateral
  double mean_aspect_ratio = 0;
  double edge_min_mm = 0, edge_max_mm = 0, edge_mean_mm = 0, edge_std_mm = 0;
  double area_mm2 = 0;
};
QualityReport quality_report(const TriMesh& mesh);

// Throws InputError with every issue, one per line, if `issues` is not empty.
void throw_if_issues(const std::vector<QualityIssue>& issues, const std::string& context);

}  // namespace systole::geometry
