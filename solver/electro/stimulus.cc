#include "solver/electro/stimulus.h"

#include <cmath>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::electro {

Stimulus::Stimulus(const ElectroMesh& mesh, StimulusSpec spec) : spec_(std::move(spec)) {
  const StimulusRegion& r = spec_.region;
  auto inside = [&](std::size_t i) {
    if (r.domain >= 0 && mesh.node_domain[i] != r.domain) return false;
    const Vec3& x = mesh.position_mm[i];
    switch (r.kind) {
      case StimulusRegion::Kind::kTagged:
        return (mesh.node_region[i] & r.region_bits) != 0;
      case StimulusRegion::Kind::kSphere:
        return (x - r.centre_mm).norm() <= r.radius_mm;
      case StimulusRegion::Kind::kBox:
        return (x.array() >= r.box_min_mm.array()).all() && (x.array() <= r.box_max_mm.array()).all();
      case StimulusRegion::Kind::kNodes:
        return false;
    }
    return false;
  };
  if (r.kind == StimulusRegion::Kind::kNodes) {
    for (auto n : r.nodes)
      if (n >= 0 && static_cast<std::size_t>(n) < mesh.node_count()) nodes_.push_back(n);
  } else {
    for (std::size_t i = 0; i < mesh.node_count(); ++i)
      if (inside(i)) nodes_.push_back(static_cast<std::int32_t>(i));
  }
  if (nodes_.empty()) {
    std::ostringstream os;
    os << "stimulus '" << spec_.name << "': its region matches no node of the mesh ("
       << mesh.node_count() << " nodes); give a region that contains at least one node";
    throw InputError(os.str());
  }
  if (!(spec_.duration_ms > 0) || (spec_.period_ms > 0 && spec_.duration_ms > spec_.period_ms)) {
    std::ostringstream os;
    os << "stimulus '" << spec_.name << "': duration_ms = " << spec_.duration_ms
       << " must be > 0 and not longer than the period (" << spec_.period_ms << " ms)";
    throw InputError(os.str());
  }
}

double Stimulus::amplitude_at(double t_ms) const {
  double local = t_ms - spec_.start_ms;
  if (local < 0) return 0.0;
  if (spec_.period_ms > 0) local = std::fmod(local, spec_.period_ms);
  return local < spec_.duration_ms ? spec_.amplitude_ua_per_cm2 : 0.0;
}

}  // namespace systole::electro
