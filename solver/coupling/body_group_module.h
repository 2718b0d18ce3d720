#pragma once
// A structure::BodyGroup (several thin-shell bodies advanced in lockstep, with contact between
// them) as a coupling::Module: the structure stage of the fsi and fsei scenes, where the LV, LA,
// aorta and the valve leaflets move together and the leaflets touch each other.
//
// Contract
// - max_step_ms() = the group's smallest stable step at its current state (contact stiffness
//   included); step(dt) = one substep of every body (BodyGroup::substep: velocity Verlet with
//   the contact forces at the new positions; throws InstabilityError naming the body, the node
//   and the time on a blow-up).
// - Inputs, held over the substeps: whatever the scene's transfers set on the bodies (external
//   loads, active tension).
// - save()/restore(): every body's positions, velocities and clock by value; restore refreshes
//   the contact loads at the restored positions (the inputs are kept).
#include <string>
#include <vector>

#include "solver/coupling/module.h"
#include "solver/structure/contact.h"

namespace systole::coupling {

class BodyGroupModule final : public Module {
 public:
  // The group must outlive the module; it must hold at least one body.
  explicit BodyGroupModule(structure::BodyGroup& group) : group_(group) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return group_.body(0).time_ms(); }
  double max_step_ms() const override { return group_.stable_step_ms(); }
  std::string step_limiter() const override { return group_.stable_step_limiter(); }
  void step(double dt_ms) override { group_.substep(dt_ms); }
  void save() override {
    saved_.resize(group_.body_count());
    for (std::size_t k = 0; k < group_.body_count(); ++k)
      saved_[k] = {group_.body(k).positions_mm(), group_.body(k).velocities_mm_per_ms(), group_.body(k).time_ms()};
  }
  void restore() override {
    for (std::size_t k = 0; k < group_.body_count(); ++k) {
      group_.body(k).set_state(saved_[k].x, saved_[k].v);
      group_.body(k).set_time_ms(saved_[k].t);
    }
    group_.refresh_contact();
  }
  structure::BodyGroup& group() { return group_; }

 private:
  struct Saved {
    std::vector<structure::Vec3> x, v;
    double t = 0;
  };
  std::string name_ = "structure";
  structure::BodyGroup& group_;
  std::vector<Saved> saved_;
};

}  // namespace systole::coupling
