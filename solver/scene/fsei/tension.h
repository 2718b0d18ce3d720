#pragma once
// Stage 1 of the coupled step (the seed's Fig. 6): the active tension on the LV and LA walls.
// Scene fsei: the EP of the LV and LA walls (eq 18–23) steps at its own step and its
// Nash–Panfilov tension (eq 24) moves to the shells' nodes; scene fsi (ours): the chambers' 0-D
// activation shapes under a prescribed peak tension. Nodes within
// electromechanics.passive_annulus_mm of the anchor ring (the fibrous annulus) and the vein caps
// carry none.
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "solver/config/scenario.h"
#include "solver/core/state_archive.h"
#include "solver/coupling/electro_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/electro/tissue.h"
#include "solver/geometry/left_heart.h"
#include "solver/lumped/activation.h"
#include "solver/structure/contact.h"

namespace systole::scene::fsei {

// A module whose clock is another's shifted by a constant (ours): EP runs from the LA stimulus,
// the scene from the LV stimulus, av_delay later.
class ShiftedClock final : public coupling::Module {
 public:
  ShiftedClock(coupling::Module& inner, double offset_ms) : inner_(inner), offset_ms_(offset_ms) {}
  const std::string& name() const override { return inner_.name(); }
  double time_ms() const override { return inner_.time_ms() - offset_ms_; }
  double offset_ms() const { return offset_ms_; }
  double max_step_ms() const override { return inner_.max_step_ms(); }
  void step(double dt_ms) override { inner_.step(dt_ms); }
  void save() override { inner_.save(); }
  void restore() override { inner_.restore(); }

 private:
  coupling::Module& inner_;
  double offset_ms_;
};

// The scene's clock as a stage of its own (fsi with fsei.coupling_order = structure_first):
// it reaches an interval's end before the shells, so the prescribed tension the shells get is
// the one at the interval's end, as with the fluid's clock in the fluid-first order.
class SceneClock final : public coupling::Module {
 public:
  explicit SceneClock(double t_ms) : t_ms_(t_ms) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_ms_; }
  double max_step_ms() const override { return 1e9; }  // no limit of its own: one step per interval
  void step(double dt_ms) override { t_ms_ += dt_ms; }
  void save() override { saved_ms_ = t_ms_; }
  void restore() override { t_ms_ = saved_ms_; }

 private:
  std::string name_ = "scene clock";
  double t_ms_, saved_ms_ = 0;
};

class ChamberTension {
 public:
  // Builds the EP (fsei) and the maps from the walls' nodes to it. The EP is pre-run alone from
  // the LA stimulus (t_EP = 0) to the LV stimulus (t_EP = av_delay; the scene's t = 0, ours),
  // or taken from `resumed` (a checkpoint's archive). Sets the tension at the start on `group`.
  ChamberTension(const config::Scenario& s, const geometry::LeftHeart& heart, structure::BodyGroup& group,
                 const StateArchive* resumed);

  bool with_ep() const { return tissue_ != nullptr; }
  // The stage module that carries the tension's clock: EP's (shifted to the scene's time) in
  // fsei; in fsi the scene's own clock when the shells go first, else none (the fluid's clock).
  coupling::Module* clock_module() const;
  // The tension transfer's data: [scene time, EP tension per EP node (fsei)], and its inverse,
  // which sets every wall node's tension on the group's LV and LA.
  void read(std::vector<double>& d, double fluid_time_ms) const;
  void write(const std::vector<double>& d);

  const electro::TissueSolver* tissue() const { return tissue_.get(); }
  long ep_steps() const;  // the tissue's own steps from its t = 0 (pre-run and checkpoints included)
  // fsei: the EP's transmembrane potential (mV) at every node of chamber c (0 LV, 1 LA); NaN
  // where the node has none.
  std::vector<double> node_vm_mv(std::size_t chamber) const;
  void export_state(StateArchive& a) const;  // fsei: the tissue, the EP module and its offset

 private:
  void set(const std::vector<double>* ep_tension_kpa);

  const config::Scenario& s_;
  structure::BodyGroup& group_;
  std::array<std::vector<std::int32_t>, 2> ep_node_;     // per chamber: the EP node of each wall node, -1: none
  std::array<std::vector<std::int32_t>, 2> ep_vm_node_;  // the same with the passive annulus (the potential)
  std::unique_ptr<electro::TissueSolver> tissue_;
  std::unique_ptr<coupling::ElectroModule> ep_module_;
  std::unique_ptr<ShiftedClock> ep_clock_;
  std::unique_ptr<SceneClock> scene_clock_;
  lumped::ChamberTiming lv_timing_, la_timing_;
  double scene_time_ms_ = 0;  // the prescribed tension's clock (the fluid's, at the sync points)
  double la_first_onset_ms_;
};

}  // namespace systole::scene::fsei
