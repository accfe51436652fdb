#include "hystbench/compensation/actuator_model.hpp"

#include <algorithm>
#include <cmath>

#include "details/validate.hpp"

namespace hystbench::compensation {

ActuatorModel::ActuatorModel(std::unique_ptr<HysteresisModel> hysteresis)
    : hysteresis_(std::move(hysteresis)) {
  details::require(hysteresis_ != nullptr, "actuator model needs a hysteresis model");
  configure(dt_);
}

ActuatorModel::ActuatorModel(const ActuatorModel& other)
    : units(other.units),
      input_min(other.input_min),
      input_max(other.input_max),
      hysteresis_(other.hysteresis_ ? other.hysteresis_->clone() : nullptr),
      creep_params_(other.creep_params_),
      dyn_params_(other.dyn_params_),
      delay_s_(other.delay_s_),
      dt_(other.dt_),
      last_input_(other.last_input_),
      creep_(other.creep_),
      dynamics_(other.dynamics_),
      delay_(other.delay_) {}

ActuatorModel& ActuatorModel::operator=(const ActuatorModel& other) {
  if (this != &other) {
    ActuatorModel copy(other);
    *this = std::move(copy);
  }
  return *this;
}

// Each setter rebuilds only its own part, so the state of the others is kept.
void ActuatorModel::set_creep(std::optional<CreepParameters> creep) {
  creep_ = creep ? CreepOperatorBank(*creep, dt_) : CreepOperatorBank();
  creep_params_ = std::move(creep);
}

void ActuatorModel::set_dynamics(std::optional<DynamicsParameters> dynamics) {
  dynamics_.reset();
  if (dynamics) dynamics_.emplace(*dynamics, dt_);
  dyn_params_ = dynamics;
}

void ActuatorModel::set_delay(double delay_s) {
  details::require(std::isfinite(delay_s) && delay_s >= 0.0, "delay_s must be >= 0");
  delay_s_ = delay_s;
  delay_ = DelayLine::of(delay_s_ / dt_);
}

void ActuatorModel::configure(double dt_s) {
  details::require(std::isfinite(dt_s) && dt_s > 0.0, "sample period must be > 0");
  dt_ = dt_s;
  if (hysteresis_) hysteresis_->set_sample_period(dt_s);
  creep_ = creep_params_ ? CreepOperatorBank(*creep_params_, dt_s) : CreepOperatorBank();
  dynamics_.reset();
  if (dyn_params_) dynamics_.emplace(*dyn_params_, dt_s);
  delay_ = DelayLine::of(delay_s_ / dt_s);
}

double ActuatorModel::step(double u) noexcept {
  last_input_ = u;
  const double ud = delay_.push(u);
  double y = hysteresis_->step(ud);
  if (!creep_.empty()) y += creep_.step(ud);
  if (dynamics_) y = dynamics_->step(y);
  return y;
}

double ActuatorModel::peek_static(double u) const noexcept {
  double y = hysteresis_->peek(u);
  if (!creep_.empty()) y += creep_.peek(u);
  return y;
}

double ActuatorModel::peek_static_at_rate(double u, double rate) const noexcept {
  double y = hysteresis_->peek_at_rate(u, rate);
  if (!creep_.empty()) y += creep_.peek(u);
  return y;
}

double ActuatorModel::rate_for_static_output(double u, double y) const noexcept {
  return hysteresis_->rate_for_output(u, creep_.empty() ? y : y - creep_.peek(u));
}

void ActuatorModel::reset(double u0) noexcept {
  last_input_ = u0;
  delay_.reset(u0);
  hysteresis_->reset(u0);
  double y = hysteresis_->peek(u0);
  if (!creep_.empty()) {
    creep_.reset(u0);
    y += creep_.peek(u0);
  }
  if (dynamics_) dynamics_->reset(y);
}

void ActuatorModel::hold(double u, std::uint64_t steps) noexcept {
  const auto stepped =
      std::min<std::uint64_t>(steps, static_cast<std::uint64_t>(std::ceil(kHoldStepsS / dt_)));
  for (std::uint64_t k = 0; k < stepped; ++k) (void)step(u);
  if (stepped == steps) return;
  // The delay holds u by now; the hysteresis at a held input stays where it is.
  if (!creep_.empty()) creep_.hold(u, steps - stepped);
  if (dynamics_) dynamics_->reset(peek_static(u));
}

std::vector<double> ActuatorModel::simulate(std::span<const double> u, double dt_s) {
  if (dt_s != dt_) configure(dt_s);
  std::vector<double> y(u.size());
  if (u.empty()) return y;
  reset(u[0]);
  for (std::size_t k = 0; k < u.size(); ++k) y[k] = step(u[k]);
  return y;
}

}  // namespace hystbench::compensation
