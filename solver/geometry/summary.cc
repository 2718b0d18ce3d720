#include "solver/geometry/summary.h"

#include <algorithm>

#include "solver/geometry/diagnostics.h"
#include "solver/geometry/quality.h"
#include "solver/geometry/tiling.h"

namespace systole::geometry {

double eulerian_spacing_mm(const config::Fluid& f) {
  return std::min({f.box_x_mm / (f.nx - 1), f.box_y_mm / (f.ny - 1), f.box_z_mm / (f.nz - 1)});
}

MarkerPlan plan_markers(const LeftHeart& heart, double target_mm) {
  MarkerPlan plan;
  plan.target_mm = target_mm;
  for (const auto& b : heart.bodies) plan.level.push_back(tiling_level(b, target_mm));
  return plan;
}

namespace {
nlohmann::json vec(const Vec3& v) { return {v.x(), v.y(), v.z()}; }
}  // namespace

nlohmann::json heart_summary(const LeftHeart& heart, const MarkerPlan& plan) {
  nlohmann::json j;
  const double zp = heart.plane.z_mm;
  const auto axis = apex_base_axis(heart.body(kLvBody));
  j["lv_cavity_volume_ml"] = cavity_volume_ml(heart.body(kLvBody), zp);
  j["la_cavity_volume_ml"] = cavity_volume_ml(heart.body(kLaBody), zp);
  j["lv_cavity_centroid_mm"] = vec(cavity_centroid_mm(heart.body(kLvBody), zp));
  j["lv_apex_base_axis"] = {{"base_centre_mm", vec(axis.base_centre_mm)},
                            {"apex_mm", vec(axis.apex_mm)},
                            {"direction", vec(axis.direction)},
                            {"length_mm", axis.length_mm}};
  j["valvular_plane"] = {{"z_mm", zp},
                         {"centre_mm", vec(heart.plane.centre_mm)},
                         {"outer_radius_mm", heart.plane.outer_radius_mm},
                         {"mitral_centre_mm", vec(heart.plane.mitral_centre_mm)},
                         {"mitral_radius_mm", heart.plane.mitral_radius_mm},
                         {"aortic_centre_mm", vec(heart.plane.aortic_centre_mm)},
                         {"aortic_radius_mm", heart.plane.aortic_radius_mm}};
  j["outflow_region"] = {{"start_mm", vec(heart.outflow.start_mm)},
                         {"end_mm", vec(heart.outflow.end_mm)},
                         {"radius_mm", heart.outflow.radius_mm}};
  const auto& l = heart.layout;
  j["layout"] = {{"lv_truncation", l.lv_truncation},
                 {"lv_polar_semi_axis_mm", l.lv_polar_semi_axis_mm},
                 {"lv_base_radius_mm", l.lv_base_radius_mm},
                 {"lv_xy_scale", l.lv_xy_scale},
                 {"la_equatorial_radius_mm", l.la_equatorial_radius_mm},
                 {"la_polar_semi_axis_mm", l.la_polar_semi_axis_mm},
                 {"la_height_mm", l.la_height_mm},
                 {"la_height_scale", l.la_height_scale},
                 {"sinus_amplitude_mm", l.sinus_amplitude_mm},
                 {"root_height_mm", l.root_height_mm},
                 {"arch_radius_mm", l.arch_radius_mm},
                 {"descending_offset_mm", l.descending_offset_mm},
                 {"mitral_coaptation_depth_mm", l.mitral_coaptation_depth_mm},
                 {"mitral_rest_depth_mm", l.mitral_rest_depth_mm},
                 {"cusp_coaptation_height_mm", l.cusp_coaptation_height_mm},
                 {"leaflet_gap_mm", l.leaflet_gap_mm},
                 {"ring_edge_mm", l.ring_edge_mm},
                 {"aortic_commissure_height_mm", l.aortic_commissure_height_mm},
                 {"aortic_crown_height_mm", l.aortic_crown_height_mm},
                 {"box_clearance_mm", vec(l.box_clearance_mm)}};
  j["marker_spacing_target_mm"] = plan.target_mm;
  std::size_t nodes = 0, tris = 0, marker_nodes = 0, marker_tris = 0;
  for (std::size_t b = 0; b < heart.bodies.size(); ++b) {
    const TriMesh& m = heart.bodies[b];
    const auto q = quality_report(m);
    const int lvl = plan.level.empty() ? 1 : plan.level[b];
    // Tiled counts: V' = V + E (m - 1) + F (m - 1)(m - 2) / 2, F' = F m^2.
    const std::size_t mn = m.node_count() + q.edges * (lvl - 1) + m.triangle_count() * (lvl - 1) * (lvl - 2) / 2;
    const std::size_t mt = m.triangle_count() * lvl * lvl;
    j["bodies"][m.name] = {{"kind", body_kind_name(m.kind)},
                           {"nodes", q.nodes},
                           {"triangles", q.triangles},
                           {"area_mm2", q.area_mm2},
                           {"min_angle_deg", q.min_angle_deg},
                           {"max_angle_deg", q.max_angle_deg},
                           {"max_aspect_ratio", q.max_aspect_ratio},
                           {"mean_aspect_ratio", q.mean_aspect_ratio},
                           {"edge_mm", {{"min", q.edge_min_mm}, {"max", q.edge_max_mm}, {"mean", q.edge_mean_mm}, {"std", q.edge_std_mm}}},
                           {"tiling_level", lvl},
                           {"marker_nodes", mn},
                           {"marker_triangles", mt}};
    nodes += m.node_count();
    tris += m.triangle_count();
    marker_nodes += mn;
    marker_tris += mt;
  }
  j["totals"] = {{"nodes", nodes}, {"triangles", tris}, {"marker_nodes", marker_nodes}, {"marker_triangles", marker_tris}};
  return j;
}

}  // namespace systole::geometry
