#pragma once
// One synchronisation interval of the coupled heart, the seed's Fig. 6, as three transfers
// between the modules of CoupledHeart run by the multirate scheduler (solver/coupling):
//   1. tension      [EP or the scene's clock] → the LV and LA shells (eq 24; tension.h)
//   2. fluid        the blood sub-cycles at its stable step with the markers at the shells'
//                   held nodes (eq 1–10); its loads (eq 11–14) go to the shells' nodes
//                   through the tiling maps' transposes (the relaxed transfer)
//   3. structure    the shells sub-cycle together with contact (eq 15–17), loads and tension
//                   held; their nodes and velocities go back to the markers
// fsei.coupling_order = structure_first (ours) runs the shells before the fluid, with the loads
// last written; strong coupling iterates the passes to fsei.strong_coupling's tolerance.
#include <cstddef>
#include <memory>
#include <vector>

#include "solver/coupling/body_group_module.h"
#include "solver/coupling/scheduler.h"
#include "solver/scene/fsei/coupled_heart.h"

namespace systole::scene::fsei {

class CoupledStep {
 public:
  // A resumed run: the fluid, the shells, the forcing and the scheduler where the checkpoint left
  // them, and the markers on the shells' nodes.
  CoupledStep(CoupledHeart& h, const Resume& resume);
  CoupledStep(const CoupledStep&) = delete;
  CoupledStep& operator=(const CoupledStep&) = delete;

  // Runs the intervals up to t_ms. A body within a cell of the box's z wall is an
  // InstabilityError naming the nearest shell node.
  void advance_to(double t_ms);
  double time_ms() const { return scheduler_->time_ms(); }

  const coupling::SchedulerStats& stats() const { return scheduler_->stats(); }
  std::size_t fluid_stage() const { return fluid_stage_; }
  std::size_t structure_stage() const { return structure_stage_; }
  std::size_t ep_stage() const { return 0; }  // fsei: EP's stage always comes first
  void export_state(StateArchive& a) const { scheduler_->export_state(a, "scheduler/"); }

 private:
  coupling::Transfer tension_transfer();
  coupling::Transfer loads_transfer();  // 2 → 3, relaxed
  coupling::Transfer nodes_transfer();  // 3 → 2
  std::vector<coupling::Stage> stages(const coupling::Transfer& tension, const coupling::Transfer& loads,
                                      const coupling::Transfer& nodes);
  coupling::SchedulerOptions scheduler_options() const;

  CoupledHeart& h_;
  coupling::BodyGroupModule structure_module_;
  std::vector<std::size_t> shell_offset_;  // the first node of each shell in the loads' data
  std::vector<bool> loaded_bodies_;        // the marker bodies whose loads the shells take
  std::size_t fluid_stage_ = 0, structure_stage_ = 0;
  std::unique_ptr<coupling::Scheduler> scheduler_;
};

}  // namespace systole::scene::fsei
