#include "solver/config/geometry_rules.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <sstream>

namespace systole::config {

// The construction these rules guard is solver/geometry/left_heart.cc (docs/geometry.md). The
// few shape formulas needed here are repeated from it on purpose (config must not depend on
// geometry); tests/geometry/rules_test.cc checks that both agree: every combination these
// rules accept builds, and the generator's own checks reject nothing the rules pass.
namespace {

constexpr double kRimMm = 2.5;          // plane between an orifice and the LV base ring
constexpr double kMinCurtainMm = 3.0;   // between the two orifices
constexpr double kLaAspect = 0.85;      // LA polar / equatorial semi-axis
constexpr double kMinGapMm = 2.0;       // between unattached bodies
constexpr double kSinusCommissureShare = 0.15;
constexpr double kRootHeightPerDiameter = 0.5;

double bisect(const std::function<double(double)>& f, double target, double lo, double hi) {
  for (int i = 0; i < 200; ++i) {
    const double mid = 0.5 * (lo + hi);
    (f(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

double truncated_fraction(double t) { return (2.0 / 3.0 + t - t * t * t / 3.0) / (1.0 + t); }

double smoothstep(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

}  // namespace

void check_geometry_rules(const Geometry& g, std::vector<std::string>& errors) {
  std::ostringstream m;
  auto emit = [&]() {
    errors.push_back(m.str());
    m.str("");
  };
  if (g.mitral_diameter_mm >= g.lv_short_axis_mm) {
    m << "geometry.mitral_diameter_mm = " << g.mitral_diameter_mm
      << " must be smaller than geometry.lv_short_axis_mm = " << g.lv_short_axis_mm;
    emit();
  }
  if (g.aortic_diameter_mm >= g.aortic_root_diameter_mm) {
    m << "geometry.aortic_diameter_mm = " << g.aortic_diameter_mm
      << " must be smaller than geometry.aortic_root_diameter_mm = " << g.aortic_root_diameter_mm;
    emit();
  }

  // LV: a prolate ellipsoid (equatorial radius a) truncated by the plane, base-apex length L,
  // holds pi a^2 L f(t) with f increasing from 0 to its maximum 0.75 at t = 0.5.
  const double a = 0.5 * g.lv_short_axis_mm, L = g.lv_long_axis_mm;
  const double v_max_ml = 0.75 * M_PI * a * a * L * 1e-3;
  double base_radius = a;
  if (g.lv_volume_ml > v_max_ml) {
    m << "geometry.lv_volume_ml = " << g.lv_volume_ml << " exceeds the largest cavity (" << v_max_ml
      << " ml) a truncated prolate ellipsoid with geometry.lv_short_axis_mm = " << g.lv_short_axis_mm
      << " and geometry.lv_long_axis_mm = " << L << " can hold; allowed: lv_volume_ml <= 0.75 pi (short/2)^2 long";
    emit();
  } else {
    const double t = bisect(truncated_fraction, g.lv_volume_ml * 1e3 / (M_PI * a * a * L), -0.999, 0.5);
    base_radius = a * std::sqrt(1 - t * t);
  }
  const double need = g.mitral_diameter_mm + g.aortic_diameter_mm + 2 * kRimMm + kMinCurtainMm;
  if (2 * base_radius < need) {
    m << "geometry.mitral_diameter_mm + geometry.aortic_diameter_mm = "
      << g.mitral_diameter_mm + g.aortic_diameter_mm << " mm (plus two " << kRimMm << " mm rims and a "
      << kMinCurtainMm << " mm curtain = " << need << " mm) do not fit in the valvular plane: the LV base ring "
      << "is " << 2 * base_radius << " mm across with geometry.lv_short_axis_mm = " << g.lv_short_axis_mm
      << ", lv_long_axis_mm = " << L << ", lv_volume_ml = " << g.lv_volume_ml
      << "; allowed: smaller orifices or a larger LV";
    emit();
  }

  // LA: sheared truncated spheroid on the mitral ring.
  const double r_m = 0.5 * g.mitral_diameter_mm;
  auto la_volume = [&](double R) {
    const double c = kLaAspect * R, tau = std::sqrt(std::max(0.0, 1 - r_m * r_m / (R * R)));
    return M_PI * R * R * c * (2.0 / 3.0 + tau - tau * tau * tau / 3.0);
  };
  const double la_min_ml = la_volume(r_m * 1.0001) * 1e-3;
  double R_la = r_m * 1.5;
  if (g.la_volume_ml <= la_min_ml) {
    m << "geometry.la_volume_ml = " << g.la_volume_ml << " is too small for an atrium standing on a mitral "
      << "orifice of geometry.mitral_diameter_mm = " << g.mitral_diameter_mm << "; allowed: la_volume_ml > "
      << la_min_ml;
    emit();
  } else {
    R_la = bisect(la_volume, g.la_volume_ml * 1e3, r_m * 1.0001, 500);
    const double c = kLaAspect * R_la, tau = std::sqrt(1 - r_m * r_m / (R_la * R_la)), y_c = tau * c;
    // Four pulmonary-vein ostia, 40 degrees either side of posterior, at y_c +- 0.35 c.
    const double r_pv = 0.5 * g.pulmonary_vein_diameter_mm;
    auto point = [&](double y, double th) {
      const double u = std::clamp((y - y_c) / c, -1.0, 1.0), r = R_la * std::sqrt(1 - u * u);
      const double shift = y <= y_c ? r - r_m : R_la - r_m;
      return std::array<double, 3>{-shift + r * std::cos(th), r * std::sin(th), y};
    };
    auto dist = [](const std::array<double, 3>& p, const std::array<double, 3>& q) {
      return std::hypot(p[0] - q[0], p[1] - q[1], p[2] - q[2]);
    };
    const auto ls = point(y_c + 0.35 * c, M_PI - 0.7), li = point(y_c - 0.35 * c, M_PI - 0.7);
    const auto rs = point(y_c + 0.35 * c, M_PI + 0.7);
    const double spacing = std::min(dist(ls, li), dist(ls, rs));
    if (g.pulmonary_vein_diameter_mm + 1.0 > spacing || y_c - 0.35 * c < r_pv + 1.0) {
      m << "geometry.pulmonary_vein_diameter_mm = " << g.pulmonary_vein_diameter_mm
        << ": four ostia do not fit on the posterior wall of an LA of geometry.la_volume_ml = " << g.la_volume_ml
        << " (centres " << spacing << " mm apart, lowest " << y_c - 0.35 * c
        << " mm above the valvular plane); allowed: pulmonary_vein_diameter_mm <= "
        << std::max(0.0, std::min(spacing - 1.0, 2 * (y_c - 0.35 * c - 1.0)));
      emit();
    }
    if (g.la_wall_mm >= R_la) {
      m << "geometry.la_wall_mm = " << g.la_wall_mm << " must be thinner than the LA radius " << R_la
        << " mm (geometry.la_volume_ml = " << g.la_volume_ml << ")";
      emit();
    }
  }

  // Mitral leaflets in the closed position: each spans its half of the orifice, from the
  // annulus down to a coaptation line at depth sqrt(length^2 - r_m^2).
  if (g.mitral_leaflet_length_mm <= r_m + 0.5) {
    m << "geometry.mitral_leaflet_length_mm = " << g.mitral_leaflet_length_mm
      << " is too short to close the mitral orifice; allowed: > geometry.mitral_diameter_mm / 2 + 0.5 = "
      << r_m + 0.5;
    emit();
  } else if (2 * base_radius >= need && g.lv_volume_ml <= v_max_ml) {
    const double t = bisect(truncated_fraction, g.lv_volume_ml * 1e3 / (M_PI * a * a * L), -0.999, 0.5);
    const double c = L / (1 + t), z0 = t * c;
    const double x_m = base_radius - kRimMm - r_m;  // |mitral centre| from the LV axis
    auto fits = [&](double length) {
      const double z_c = std::sqrt(length * length - r_m * r_m);
      if (z_c >= L - 2 * kMinGapMm) return false;
      for (int i = 0; i <= 50; ++i) {
        const double z = z_c * i / 50, u = (z - z0) / c;
        const double r_lv = a * std::sqrt(std::max(0.0, 1 - u * u));
        if (r_lv < x_m + r_m * (1 - z / z_c) + 1.0) return false;
      }
      return true;
    };
    if (!fits(g.mitral_leaflet_length_mm)) {
      double lo = r_m + 0.5, hi = g.mitral_leaflet_length_mm;
      for (int i = 0; i < 60; ++i) (fits(0.5 * (lo + hi)) ? lo : hi) = 0.5 * (lo + hi);
      m << "geometry.mitral_leaflet_length_mm = " << g.mitral_leaflet_length_mm
        << " is longer than the LV can hold: the closed leaflets would reach the LV wall or apex "
        << "(geometry.lv_long_axis_mm = " << L << ", lv_short_axis_mm = " << g.lv_short_axis_mm
        << "); allowed: <= " << lo;
      emit();
    }
  }
  if (g.mitral_leaflet_thickness_mm >= 0.5 * g.mitral_leaflet_length_mm) {
    m << "geometry.mitral_leaflet_thickness_mm = " << g.mitral_leaflet_thickness_mm
      << " must be less than half of geometry.mitral_leaflet_length_mm = " << g.mitral_leaflet_length_mm;
    emit();
  }
  if (g.aortic_leaflet_thickness_mm >= 0.25 * g.aortic_diameter_mm) {
    m << "geometry.aortic_leaflet_thickness_mm = " << g.aortic_leaflet_thickness_mm
      << " must be less than a quarter of geometry.aortic_diameter_mm = " << g.aortic_diameter_mm;
    emit();
  }

  // Aorta: the sinuses bulge beyond the ascending aorta / arch; the root must clear the LA.
  const double R_root = 0.5 * g.aortic_root_diameter_mm, r_arch = 0.5 * g.aortic_arch_diameter_mm;
  const double r_a = 0.5 * g.aortic_diameter_mm;
  if (R_root <= r_arch) {
    m << "geometry.aortic_root_diameter_mm = " << g.aortic_root_diameter_mm
      << " must exceed geometry.aortic_arch_diameter_mm = " << g.aortic_arch_diameter_mm
      << " (the sinuses of Valsalva bulge beyond the ascending aorta)";
    emit();
  } else if (2 * base_radius >= need) {
    const double y_stj = kRootHeightPerDiameter * g.aortic_root_diameter_mm;
    auto base = [&](double s) { return r_a + (r_arch - r_a) * smoothstep(s / y_stj); };
    auto peak = [&](double amp) {
      double mx = 0;
      for (int i = 0; i <= 400; ++i) {
        const double s = y_stj * i / 400;
        mx = std::max(mx, base(s) + amp * std::sin(M_PI * s / y_stj));
      }
      return mx;
    };
    const double amp = bisect(peak, R_root, 0, 2 * R_root);
    const double curtain = 2 * base_radius - 2 * kRimMm - 2 * r_m - 2 * r_a;  // between orifice edges
    double gap = 1e300;
    for (int i = 0; i <= 60; ++i)
      for (int j = 0; j <= 72; ++j) {
        const double s = y_stj * i / 60, th = 2 * M_PI * j / 72;
        const double lobe = kSinusCommissureShare + (1 - kSinusCommissureShare) * 0.5 * (1 + std::cos(3 * th));
        const double r = base(s) + lobe * amp * std::sin(M_PI * s / y_stj);
        gap = std::min(gap, curtain + r_a + r * std::cos(th));
      }
    if (gap < kMinGapMm) {
      m << "geometry.aortic_root_diameter_mm = " << g.aortic_root_diameter_mm
        << " makes the aortic root reach the left atrium (gap " << gap << " mm < " << kMinGapMm
        << " mm) with geometry.aortic_diameter_mm = " << g.aortic_diameter_mm << ", mitral_diameter_mm = "
        << g.mitral_diameter_mm << " and an LV base ring of " << 2 * base_radius
        << " mm; allowed: a smaller root or orifices, or a wider LV";
      emit();
    }
  }
  if (g.aorta_wall_mm >= 0.5 * g.aortic_descending_diameter_mm) {
    m << "geometry.aorta_wall_mm = " << g.aorta_wall_mm
      << " must be less than the descending aortic radius geometry.aortic_descending_diameter_mm / 2 = "
      << 0.5 * g.aortic_descending_diameter_mm;
    emit();
  }
  if (g.lv_wall_mm >= a) {
    m << "geometry.lv_wall_mm = " << g.lv_wall_mm << " must be less than geometry.lv_short_axis_mm / 2 = " << a;
    emit();
  }
  // Resolution: at least 12 nodes around the aortic orifice.
  if (g.target_edge_mm > M_PI * g.aortic_diameter_mm / 12) {
    m << "geometry.target_edge_mm = " << g.target_edge_mm << " is too coarse for the aortic orifice of "
      << "geometry.aortic_diameter_mm = " << g.aortic_diameter_mm << "; allowed: <= pi aortic_diameter_mm / 12 = "
      << M_PI * g.aortic_diameter_mm / 12;
    emit();
  }
}

}  // namespace systole::config
