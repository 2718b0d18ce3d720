#include "solver/scene/fsei/wall_shear.h"

namespace systole::scene::fsei {

using geometry::Vec3;

std::vector<std::vector<double>> node_wss_pa(const CoupledHeart& h, const ibm::WallShear& w) {
  std::vector<int> link_of_marker_body(h.markers.bodies().size(), -1);
  for (std::size_t li = 0; li < h.links.size(); ++li)
    link_of_marker_body[static_cast<std::size_t>(h.links[li].marker_body)] = static_cast<int>(li);
  const ibm::MarkerArrays& ma = h.markers.markers();
  std::vector<std::vector<Vec3>> sum(h.links.size());  // per link, per tiled node: (Σ a v, Σ a, 0)
  for (std::size_t li = 0; li < h.links.size(); ++li) sum[li].assign(h.links[li].map.size(), Vec3::Zero());
  for (std::size_t mk = 0; mk < ma.size(); ++mk) {
    const int li = link_of_marker_body[static_cast<std::size_t>(ma.body[mk])];
    if (li < 0 || !h.markers.active(mk)) continue;
    const double v = marker_wss_pa(w, mk, h.scales.pa_per_unit), a = ma.area[mk];
    for (int c = 0; c < 3; ++c) sum[static_cast<std::size_t>(li)][static_cast<std::size_t>(ma.node[mk][c])] += Vec3(a * v, a, 0);
  }
  std::vector<std::vector<Vec3>> acc(h.group.body_count());
  for (std::size_t b = 0; b < h.group.body_count(); ++b) acc[b].assign(h.group.body(b).node_count(), Vec3::Zero());
  for (std::size_t li = 0; li < h.links.size(); ++li) {
    const std::vector<Vec3> parent = h.links[li].map.spread(sum[li], h.group.body(h.links[li].shell).node_count());
    for (std::size_t n = 0; n < parent.size(); ++n) acc[h.links[li].shell][n] += parent[n];
  }
  std::vector<std::vector<double>> out(h.group.body_count());
  for (std::size_t b = 0; b < acc.size(); ++b) {
    out[b].resize(acc[b].size());
    for (std::size_t n = 0; n < acc[b].size(); ++n) out[b][n] = acc[b][n].y() > 0 ? acc[b][n].x() / acc[b][n].y() : 0.0;
  }
  return out;
}

}  // namespace systole::scene::fsei
