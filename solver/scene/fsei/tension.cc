#include "solver/scene/fsei/tension.h"

#include <cmath>
#include <limits>

#include "solver/scene/chamber_walls.h"
#include "solver/scene/left_heart_ep.h"
#include "solver/scene/fsei/bodies.h"
#include "solver/scene/fsei_scene.h"

namespace systole::scene::fsei {

ChamberTension::ChamberTension(const config::Scenario& s, const geometry::LeftHeart& heart,
                               structure::BodyGroup& group, const StateArchive* resumed)
    : s_(s),
      group_(group),
      lv_timing_(lumped::ChamberTiming::lv(s)),
      la_timing_(lumped::ChamberTiming::la(s)),
      // The first beat starts at the LV stimulus with the LA at rest: its walls carry no tension
      // before its first stimulus (ours: the stress-free LA is not the end of an atrial
      // contraction; a sudden atrial tension at t = 0 is a jolt the blood cannot follow).
      la_first_onset_ms_(s.period_ms() - s.av_delay_ms) {
  const bool with_ep = s.scene == "fsei";
  if (s.fsei.coupling_order == "structure_first" && !with_ep)
    scene_clock_ = std::make_unique<SceneClock>(resumed ? resumed->scalar("scene/time_ms") : 0.0);
  const geometry::TriMesh& lv_mesh = heart.body(geometry::kLvBody);
  const geometry::TriMesh& la_mesh = heart.body(geometry::kLaBody);
  std::vector<std::array<std::int32_t, 2>> source;
  if (with_ep) {
    LeftHeartEp ep = left_heart_ep(s, lv_mesh, la_mesh);
    source = ep.mesh.source_node;
    tissue_ = std::make_unique<electro::TissueSolver>(std::move(ep.mesh), std::move(ep.options));
  }
  for (std::size_t c = 0; c < 2; ++c) {
    const geometry::TriMesh& mesh = c == 0 ? lv_mesh : la_mesh;
    auto& map = ep_node_[c];
    map.assign(mesh.node_count(), with_ep ? -1 : 0);
    if (with_ep) {
      for (std::size_t k = 0; k < source.size(); ++k)
        if (source[k][0] == static_cast<int>(c)) map[static_cast<std::size_t>(source[k][1])] = static_cast<std::int32_t>(k);
      ep_vm_node_[c] = map;
    } else {  // fsi: every wall node outside the vein caps
      for (std::size_t i = 0; i < mesh.node_count(); ++i)
        if (mesh.region[i] & geometry::kPvOstiumAny) map[i] = -1;
    }
    clear_passive_annulus(mesh, s.electromechanics.passive_annulus_mm, map);
  }
  if (!with_ep) {
    set(nullptr);
    return;
  }
  ep_module_ = std::make_unique<coupling::ElectroModule>(*tissue_);
  // The scene's t = 0 is the EP clock after the pre-run, exactly: the clock is a sum of n
  // steps, and an offset of n dt would leave the scene's clock 1e-12 ms off the fluid's, so the
  // scheduler's first interval would end on a 1e-12 ms sliver that the fluid steps (its pressure
  // then blew up at 0.3 ms).
  double offset_ms = 0;
  if (resumed) {
    tissue_->import_state(*resumed, "ep/");
    ep_module_->import_state(*resumed, "ep_module/");
    offset_ms = resumed->scalar("ep_module/offset_ms");
  } else {
    const double dt = s.electro.time_step_ms;
    const long n = std::lround(s.av_delay_ms / dt);
    for (long i = 0; i < n; ++i) ep_module_->step(dt);
    offset_ms = ep_module_->time_ms();
  }
  ep_clock_ = std::make_unique<ShiftedClock>(*ep_module_, offset_ms);
  set(&tissue_->active_tension_kpa());
}

coupling::Module* ChamberTension::clock_module() const {
  if (ep_clock_) return ep_clock_.get();
  return scene_clock_.get();
}

void ChamberTension::read(std::vector<double>& d, double fluid_time_ms) const {
  d.assign(1, ep_clock_ ? ep_clock_->time_ms() : scene_clock_ ? scene_clock_->time_ms() : fluid_time_ms);
  if (tissue_) d.insert(d.end(), tissue_->active_tension_kpa().begin(), tissue_->active_tension_kpa().end());
}

void ChamberTension::write(const std::vector<double>& d) {
  scene_time_ms_ = d[0];
  if (tissue_) {
    const std::vector<double> tau(d.begin() + 1, d.end());
    set(&tau);
  } else {
    set(nullptr);
  }
}

void ChamberTension::set(const std::vector<double>* ep_tension_kpa) {
  for (std::size_t c = 0; c < 2; ++c) {
    if (c == 1 && scene_time_ms_ < la_first_onset_ms_ - 1e-9) {
      group_.body(kLa).set_active_tension(std::vector<double>(group_.body(kLa).node_count(), 0.0));
      continue;
    }
    structure::ShellModel& m = group_.body(c == 0 ? kLv : kLa);
    std::vector<double> tau(m.node_count(), 0.0);
    const double prescribed =
        ep_tension_kpa ? 0.0
                       : prescribed_peak_tension_kpa(s_.fsei, c == 0 ? Chamber::lv : Chamber::la) *
                             (c == 0 ? lv_timing_ : la_timing_).activation(1e-3 * scene_time_ms_);
    for (std::size_t i = 0; i < tau.size(); ++i) {
      const std::int32_t e = ep_node_[c][i];
      if (e < 0) continue;
      tau[i] = ep_tension_kpa ? (*ep_tension_kpa)[static_cast<std::size_t>(e)] : prescribed;
    }
    m.set_active_tension(std::move(tau));
  }
}

long ChamberTension::ep_steps() const {
  return tissue_ ? std::lround(tissue_->time_ms() / s_.electro.time_step_ms) : 0;
}

std::vector<double> ChamberTension::node_vm_mv(std::size_t chamber) const {
  const std::vector<std::int32_t>& map = ep_vm_node_.at(chamber);
  std::vector<double> vm(map.size(), std::numeric_limits<double>::quiet_NaN());
  for (std::size_t i = 0; i < map.size(); ++i)
    if (map[i] >= 0) vm[i] = tissue_->vm_mv()[static_cast<std::size_t>(map[i])];
  return vm;
}

void ChamberTension::export_state(StateArchive& a) const {
  if (!tissue_) return;
  tissue_->export_state(a, "ep/");
  ep_module_->export_state(a, "ep_module/");
  a.put_scalar("ep_module/offset_ms", ep_clock_->offset_ms());
}

}  // namespace systole::scene::fsei
