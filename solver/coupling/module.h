#pragma once
// What the multirate scheduler (scheduler.h) needs from a physics module, and nothing more.
//
// Contract
// - A Module owns its state and its clock (time_ms()). It advances only through step(dt_ms),
//   by exactly dt_ms, with the inputs last written into it (by the scene's transfers).
// - max_step_ms() is the largest step the module may take from its CURRENT state: its
//   stability limit (an explicit shell's CFL-like bound, recomputed as the Fung law stiffens),
//   or its accuracy step for modules run at a fixed step (EP, the 0-D circulation) (ours).
//   It must be > 0 and finite; the scheduler never asks for more (except when a test scales the
//   limit on purpose, SchedulerOptions::step_limit_factor).
// - step() throws systole::InstabilityError naming the module, the place (node, cell, ...) and
//   the time when its state blows up (non-finite values, a strain or energy beyond its limits).
//   A module never returns non-finite outputs.
// - save() keeps an in-memory copy of the whole state (clock included); restore() returns to
//   it, any number of times. Strong coupling repeats a synchronisation interval this way.
//   Inputs written by transfers are NOT state: restore() keeps the latest inputs (they are the
//   new iterate the repeated interval is for).
#include <string>

namespace systole::coupling {

class Module {
 public:
  virtual ~Module() = default;
  virtual const std::string& name() const = 0;
  virtual double time_ms() const = 0;
  virtual double max_step_ms() const = 0;
  // What sets max_step_ms() (a body, node, cell), for diagnoses; empty: not known.
  virtual std::string step_limiter() const { return {}; }
  virtual void step(double dt_ms) = 0;
  virtual void save() = 0;
  virtual void restore() = 0;
};

}  // namespace systole::coupling
