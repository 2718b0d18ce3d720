#include "solver/scene/fsei/coupled_step.h"

#include <algorithm>
#include <sstream>

#include "solver/core/errors.h"

namespace systole::scene::fsei {

using geometry::Vec3;

CoupledStep::CoupledStep(CoupledHeart& h, const Resume& resume) : h_(h), structure_module_(h.group) {
  shell_offset_.assign(h.group.body_count() + 1, 0);
  for (std::size_t b = 0; b < h.group.body_count(); ++b) shell_offset_[b + 1] = shell_offset_[b] + h.group.body(b).node_count();
  // Only the bodies linked to a shell are loaded: the rigid plane's loads are never used, and its
  // markers (16 528 of 98 494 at coarse, two-sided: two probes each) are not probed (ours, for cost).
  loaded_bodies_.assign(h.markers.bodies().size(), false);
  for (const Link& l : h.links) loaded_bodies_[static_cast<std::size_t>(l.marker_body)] = true;
  const coupling::Transfer tension = tension_transfer(), loads = loads_transfer(), nodes = nodes_transfer();
  std::vector<coupling::Stage> st = stages(tension, loads, nodes);
  const auto stage_of = [&](const coupling::Module* m) {
    return static_cast<std::size_t>(
        std::find_if(st.begin(), st.end(), [&](const coupling::Stage& x) { return x.module == m; }) - st.begin());
  };
  fluid_stage_ = stage_of(&h.fluid_module);
  structure_stage_ = stage_of(&structure_module_);
  const coupling::SchedulerOptions so = scheduler_options();
  if (resume.directory) {
    h.fluid.restore_checkpoint(*resume.directory / "fluid.h5");
    h.group.import_state(resume.state, "structure/");
    h.forcing.import_state(resume.state, "ibm/");  // the carry-over forcing's carried force, if any
    std::vector<double> d;  // the markers on the shells' nodes (what the last interval had set)
    nodes.read(d);
    nodes.write(d);
  }
  scheduler_ = std::make_unique<coupling::Scheduler>(std::move(st), so);
  if (resume.directory) scheduler_->import_state(resume.state, "scheduler/");
}

coupling::Transfer CoupledStep::tension_transfer() {
  return {"active_tension", [this](std::vector<double>& d) { h_.tension.read(d, h_.fluid_module.time_ms()); },
          [this](const std::vector<double>& d) { h_.tension.write(d); }, false};
}

coupling::Transfer CoupledStep::loads_transfer() {
  auto read = [this](std::vector<double>& d) {  // the markers' loads (eq 11–14) spread to the shells' nodes, mN
    const ibm::MarkerLoads L = h_.fluid_module.loads(loaded_bodies_);
    d.assign(3 * shell_offset_.back(), 0.0);
    for (const Link& l : h_.links) {
      if (!h_.markers.bodies()[static_cast<std::size_t>(l.marker_body)].active) continue;
      const std::vector<Vec3> f =
          l.map.spread(L.nodal_force.at(static_cast<std::size_t>(l.marker_body)), h_.group.body(l.shell).node_count());
      for (std::size_t n = 0; n < f.size(); ++n)
        for (int c = 0; c < 3; ++c) d[3 * (shell_offset_[l.shell] + n) + c] += h_.scales.force_scale_mn * f[n][c];
    }
  };
  auto write = [this](const std::vector<double>& d) {  // the shells' external loads, the aorta's pre-tension added
    const std::size_t aorta = shell_index(geometry::kAortaBody);
    for (std::size_t b = 0; b < h_.group.body_count(); ++b) {
      std::vector<Vec3> f(h_.group.body(b).node_count());
      for (std::size_t n = 0; n < f.size(); ++n) {
        const std::size_t i = 3 * (shell_offset_[b] + n);
        f[n] = Vec3(d[i], d[i + 1], d[i + 2]);
      }
      if (b == aorta)
        h_.aorta.apply(h_.fluid_module.time_ms(), h_.heart.body(geometry::kAortaBody), h_.group.body(b), f);
      h_.group.body(b).set_external_loads(std::move(f));
    }
  };
  return {"hydrodynamic loads", read, write, true};
}

coupling::Transfer CoupledStep::nodes_transfer() {
  auto read = [this](std::vector<double>& d) {  // the shells' nodes on the tiled markers, nondimensional
    d.clear();
    for (const Link& l : h_.links) {
      const auto x = l.map.interpolate(h_.group.body(l.shell).positions_mm());
      const auto v = l.map.interpolate(h_.group.body(l.shell).velocities_mm_per_ms());
      for (std::size_t n = 0; n < x.size(); ++n)
        for (int c = 0; c < 3; ++c) d.push_back(x[n][c] / kDmMm);
      for (std::size_t n = 0; n < v.size(); ++n)
        for (int c = 0; c < 3; ++c) d.push_back(v[n][c] / kUmMmPerMs);
    }
  };
  auto write = [this](const std::vector<double>& d) {
    std::size_t at = 0;
    for (const Link& l : h_.links) {
      const std::size_t n = l.map.size();
      std::vector<Vec3> x(n), v(n);
      for (std::size_t q = 0; q < n; ++q, at += 3) x[q] = Vec3(d[at], d[at + 1], d[at + 2]);
      for (std::size_t q = 0; q < n; ++q, at += 3) v[q] = Vec3(d[at], d[at + 1], d[at + 2]);
      h_.fluid_module.set_body_nodes(l.marker_body, x, v);
    }
  };
  return {"structure nodes to the markers", read, write, false};
}

// A pass: fluid_first (the seed's Fig. 6): [EP,] the fluid, the shells with its loads;
// structure_first (ours): [EP or the scene's clock,] the shells with the loads last written, the
// fluid at their new shape. The loads are the relaxed transfer either way.
std::vector<coupling::Stage> CoupledStep::stages(const coupling::Transfer& tension, const coupling::Transfer& loads,
                                                 const coupling::Transfer& nodes) {
  coupling::Module* fluid = &h_.fluid_module;
  coupling::Module* shells = &structure_module_;
  coupling::Module* clock = h_.tension.clock_module();
  if (h_.s.fsei.coupling_order == "structure_first") return {{clock, {tension}}, {shells, {nodes}}, {fluid, {loads}}};
  if (h_.tension.with_ep()) return {{clock, {tension}}, {fluid, {loads}}, {shells, {nodes}}};
  return {{fluid, {tension, loads}}, {shells, {nodes}}};
}

coupling::SchedulerOptions CoupledStep::scheduler_options() const {
  const config::Scenario& s = h_.s;
  const bool structure_first = s.fsei.coupling_order == "structure_first";
  coupling::SchedulerOptions so;
  so.sync_step_ms = s.fsei.sync_step_ms;
  // fluid_step: the intervals follow the fluid's stage (ours; EP's tissue keeps its own fixed
  // grid whatever the interval: coupling::ElectroModule)
  if (s.fsei.sync_interval == "fluid_step") so.interval_stage = static_cast<int>(fluid_stage_);
  so.interval_stage_steps = s.fsei.fluid_steps_per_interval;
  so.mode = s.fsei.strong_coupling ? coupling::CouplingMode::strong : coupling::CouplingMode::loose;
  so.strong_tolerance = s.coupling.strong_tolerance;
  so.strong_max_iterations = s.coupling.strong_max_iterations;
  so.relaxation = s.coupling.relaxation == "iqn_ils"    ? coupling::Relaxation::iqn_ils
                  : s.coupling.relaxation == "constant" ? coupling::Relaxation::constant
                  : s.coupling.relaxation == "none"     ? coupling::Relaxation::none
                                                        : coupling::Relaxation::aitken;
  so.iqn_reuse_intervals = s.coupling.iqn_reuse_intervals;
  // structure_first: the shells consume the loads before the fluid makes them, so a pass's change
  // of the loads is a fixed-point residual from the first pass on (ours)
  so.first_pass_residual = structure_first;
  so.first_pass_predictor =
      s.fsei.first_pass_predictor == "linear" ? coupling::FirstPassPredictor::linear : coupling::FirstPassPredictor::last;
  return so;
}

void CoupledStep::advance_to(double t_ms) {
  try {
    scheduler_->advance_to(t_ms);
  } catch (const ibm::WallProximityError& e) {
    // a body came within a cell of the box's z wall: a diagnosis with the nearest shell node
    const Vec3 at_mm = e.point() * kDmMm;
    std::size_t best_body = 0, best_node = 0;
    double best = 1e300;
    for (std::size_t b = 0; b < h_.group.body_count(); ++b) {
      const std::vector<Vec3>& x = h_.group.body(b).positions_mm();
      for (std::size_t n = 0; n < x.size(); ++n)
        if ((x[n] - at_mm).squaredNorm() < best) best = (x[n] - at_mm).squaredNorm(), best_body = b, best_node = n;
    }
    std::ostringstream place, what;
    place.precision(4);
    place << "body '" << h_.group.body(best_body).name() << "' node " << best_node << " (a marker or load probe at ("
          << at_mm.x() << ", " << at_mm.y() << ", " << at_mm.z() << ") mm)";
    what << "a body moved within a cell of the box's z wall (z in [0, " << h_.s.fluid.box_z_mm
         << "] mm): the immersed boundary's support would leave the fluid";
    throw InstabilityError("immersed boundary", place.str(), 1e-3 * scheduler_->time_ms(), what.str());
  }
}

}  // namespace systole::scene::fsei
