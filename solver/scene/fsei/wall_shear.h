#pragma once
// The wall shear stress of the coupled scene (eq 27, extrapolated to the wall:
// ibm::wall_shear_stress) in Pa: per marker the larger of its two sides' (leaflets); per shell
// node the area-weighted mean of its tiles' values carried back by the tiling maps (ours).
#include <algorithm>
#include <cstddef>
#include <vector>

#include "solver/ibm/loads.h"
#include "solver/scene/fsei/coupled_heart.h"

namespace systole::scene::fsei {

inline double marker_wss_pa(const ibm::WallShear& w, std::size_t marker, double pa_per_unit) {
  return std::max(w.plus[marker], w.minus[marker]) * pa_per_unit;
}

// Per group body, per shell node (0 where no active marker touches the node).
std::vector<std::vector<double>> node_wss_pa(const CoupledHeart& h, const ibm::WallShear& w);

}  // namespace systole::scene::fsei
