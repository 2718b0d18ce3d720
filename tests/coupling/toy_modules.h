#pragma once
// Toy modules with exact solutions for the scheduler's tests.
#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "solver/core/errors.h"
#include "solver/coupling/module.h"

namespace systole::coupling::testing {

// A mass on springs: m x'' = −k x − k_c (x − x_partner) + force, velocity Verlet, with the
// partner position and the force as inputs held constant over a step. Its limit is
// `limit_fraction` of Verlet's bound 2/ω. Blow-up detection: energy above `energy_limit`.
class Oscillator final : public Module {
 public:
  Oscillator(std::string name, double mass, double k, double k_coupling, double x0, double limit_fraction)
      : name_(std::move(name)), m_(mass), k_(k), kc_(k_coupling), x_(x0), limit_fraction_(limit_fraction) {
    energy_limit_ = 1e3 * std::max(0.5 * (k_ + kc_) * x0 * x0, 0.5);
  }
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_; }
  double max_step_ms() const override { return limit_fraction_ * 2 / std::sqrt((k_ + kc_) / m_); }
  void step(double dt) override {
    v_ += 0.5 * dt * acceleration();
    x_ += dt * v_;
    v_ += 0.5 * dt * acceleration();
    t_ += dt;
    ++steps_;
    const double energy = 0.5 * m_ * v_ * v_ + 0.5 * (k_ + kc_) * x_ * x_;
    if (!std::isfinite(energy) || energy > energy_limit_)
      throw InstabilityError(name_, "node 0", t_ / 1000, "energy " + std::to_string(energy) + " above the limit");
  }
  void save() override { saved_ = {x_, v_, t_}; }
  void restore() override {
    x_ = saved_[0];
    v_ = saved_[1];
    t_ = saved_[2];
  }
  double acceleration() const { return (-k_ * x_ - kc_ * (x_ - partner_) + force_) / m_; }
  double x() const { return x_; }
  long long steps() const { return steps_; }
  double partner_ = 0, force_ = 0;  // inputs

 private:
  std::string name_;
  double m_, k_, kc_, x_, v_ = 0, t_ = 0, limit_fraction_, energy_limit_;
  std::vector<double> saved_{0, 0, 0};
  long long steps_ = 0;
};

// An "added mass" fluid: its output load is −m_a times the structure's acceleration (input).
// Its own step is unlimited by stability; it takes `step_ms` steps (an accuracy step).
class AddedMassFluid final : public Module {
 public:
  AddedMassFluid(double added_mass, double step_ms) : m_a_(added_mass), step_(step_ms) {}
  const std::string& name() const override { return name_; }
  double time_ms() const override { return t_; }
  double max_step_ms() const override { return step_; }
  void step(double dt) override { t_ += dt; }
  void save() override { saved_ = t_; }
  void restore() override { t_ = saved_; }
  double load() const { return -m_a_ * structure_acceleration_; }
  double structure_acceleration_ = 0;  // input

 private:
  std::string name_ = "toy_fluid";
  double m_a_, step_, t_ = 0, saved_ = 0;
};

}  // namespace systole::coupling::testing
