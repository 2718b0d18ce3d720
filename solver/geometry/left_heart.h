#pragma once
// The procedural left heart (MODEL.md §1), built from the scenario's geometry variant.
// See docs/geometry.md for the construction and every (ours) choice; in short:
// - valvular plane: the disk closing the LV base, pierced by the mitral and aortic orifices;
// - LV: a prolate ellipsoid of equatorial diameter lv_short_axis_mm truncated by the plane so
//   that the base-apex length is lv_long_axis_mm and the closed cavity holds lv_volume_ml;
// - LA: a sheared truncated spheroid on the mitral ring, 4 pulmonary-vein ostia posteriorly;
// - mitral leaflets (anterior, posterior) and three aortic cusps, in the closed position;
// - aorta: root with three sinuses, 180-degree arch, descending aorta with an outflow region.
// Units: mm, ml. Frame: z along the LV long axis pointing to the apex, origin at the fluid box
// corner (the heart is centred in the box).
#include <string_view>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/geometry/tri_mesh.h"

namespace systole::geometry {

// Body names, in the order of LeftHeart::bodies.
inline constexpr std::string_view kValvularPlaneBody = "valvular_plane";
inline constexpr std::string_view kLvBody = "lv";
inline constexpr std::string_view kLaBody = "la";
inline constexpr std::string_view kMitralAnteriorBody = "mitral_anterior";
inline constexpr std::string_view kMitralPosteriorBody = "mitral_posterior";
inline constexpr std::string_view kAorticCuspBodies[3] = {"aortic_cusp_1", "aortic_cusp_2",
                                                          "aortic_cusp_3"};
inline constexpr std::string_view kAortaBody = "aorta";

struct ValvularPlane {
  double z_mm;
  Vec3 centre_mm;          // on the LV long axis
  double outer_radius_mm;  // the LV base ring (vertex radius of its polygon)
  Vec3 mitral_centre_mm;
  double mitral_radius_mm;
  Vec3 aortic_centre_mm;
  double aortic_radius_mm;
};

// Where the Darcy afterload sits: a cylinder around the end of the descending aorta.
struct OutflowRegion {
  Vec3 start_mm, end_mm;
  double radius_mm;
};

// Derived numbers of the construction (reported in the summary and docs).
struct HeartLayout {
  double lv_truncation = 0;                // t: ellipsoid centre sits t*c below the plane
  double lv_polar_semi_axis_mm = 0;        // c = L / (1 + t)
  double lv_base_radius_mm = 0;            // base ring (after the volume correction)
  double lv_xy_scale = 1;                  // discrete volume correction of the LV
  double la_equatorial_radius_mm = 0;
  double la_polar_semi_axis_mm = 0;
  double la_height_mm = 0;
  double la_height_scale = 1;              // discrete volume correction of the LA
  double sinus_amplitude_mm = 0;
  double root_height_mm = 0;
  double arch_radius_mm = 0;               // centreline radius of the 180-degree arch
  double descending_offset_mm = 0;         // horizontal distance ascending -> descending axis
  double mitral_coaptation_depth_mm = 0;   // depth of the closed mitral free edge
  double mitral_rest_depth_mm = 0;         // depth of the rest shape's free edge (0: no rest shape)
  double cusp_coaptation_height_mm = 0;    // height of the closed aortic cusp tips
  double leaflet_gap_mm = 0;               // gap between neighbouring leaflets at closure
  double ring_edge_mm = 0;                 // node spacing on the plane and the orifice rings
  double aortic_commissure_height_mm = 0;  // crown: commissures above the plane (0: flat cusps)
  double aortic_crown_height_mm = 0;       // anchors tagged aortic_annulus lie up to this height
                                           // above the plane (the cusps' crown-shaped attachment
                                           // and the root wall held below it); 0: flat cusps
  Vec3 box_clearance_mm = Vec3::Zero();    // smallest distance to the box walls (x, y, z)
};

struct LeftHeart {
  std::vector<TriMesh> bodies;  // valvular_plane, lv, la, mitral_anterior, mitral_posterior,
                                // aortic_cusp_1..3, aorta
  ValvularPlane plane;
  Vec3 lv_axis_direction = Vec3::UnitZ();  // base -> apex
  OutflowRegion outflow;
  HeartLayout layout;

  const TriMesh& body(std::string_view name) const;  // throws std::out_of_range
  TriMesh& body(std::string_view name);
  std::vector<const TriMesh*> body_pointers() const;
};

// Minimum distance between the surfaces of unattached bodies (LV, LA, aorta) (ours).
inline constexpr double kMinBodyGapMm = 2.0;
// Minimum distance from any node to the fluid box walls (ours).
inline constexpr double kMinBoxClearanceMm = 2.0;

// Builds, checks (quality, intersections, clearances, box) and returns the heart. Throws
// InputError naming the parameters when the combination cannot be built.
LeftHeart build_left_heart(const config::Geometry& geometry, const config::Fluid& fluid);

}  // namespace systole::geometry
