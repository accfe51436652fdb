#include "hystbench/sim/simulated_stage.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace hystbench::sim {

SimulatedStage::SimulatedStage(const SimulatedStageConfig& config, double dt_s) : config_(config) {
  validate(config_);
  const std::size_t n = config_.axes.size();
  for (const StageAxisConfig& axis : config_.axes) {
    axes_.push_back(std::make_unique<SimulatedActuator>(axis.actuator, dt_s));
  }
  if (config_.coupling.enabled && !config_.coupling.gains.empty() && n > 1) {
    const compensation::DynamicsParameters mode{config_.coupling.shared_mode_hz,
                                                config_.coupling.shared_damping_ratio};
    shared_.assign(n, compensation::SecondOrderDynamics(mode, dt_s));
    shared_out_.assign(n, 0.0);
  }
  strokes_.assign(n, 0.0);
  reset();
}

double SimulatedStage::cross(std::size_t i) const noexcept {
  double sum = 0.0;
  const std::vector<double>& gains = config_.coupling.gains[i];
  for (std::size_t j = 0; j < shared_out_.size(); ++j) sum += gains[j] * shared_out_[j];
  return sum;
}

void SimulatedStage::step(std::span<const double> u_volts, std::span<double> y_um) noexcept {
  const std::size_t n = axes_.size();
  constexpr double kHold = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < n; ++i) {
    strokes_[i] = axes_[i]->stroke(i < u_volts.size() ? u_volts[i] : kHold);
  }
  for (std::size_t j = 0; j < shared_.size(); ++j) shared_out_[j] = shared_[j].step(strokes_[j]);
  for (std::size_t i = 0; i < n; ++i) {
    double x = axes_[i]->structure(strokes_[i]);
    if (coupled()) x += cross(i);
    const double y = axes_[i]->measure(x);
    if (i < y_um.size()) y_um[i] = y;
  }
}

void SimulatedStage::reset(std::span<const double> u0) noexcept {
  const std::size_t n = axes_.size();
  for (std::size_t i = 0; i < n; ++i) {
    axes_[i]->reset(i < u0.size() ? u0[i] : axes_[i]->input_min());
    strokes_[i] = axes_[i]->last_stroke();
  }
  if (!coupled()) return;
  for (std::size_t j = 0; j < n; ++j) {
    shared_[j].reset(strokes_[j]);
    shared_out_[j] = strokes_[j];
  }
  for (std::size_t i = 0; i < n; ++i) axes_[i]->settle_measurement(strokes_[i] + cross(i));
}

}  // namespace hystbench::sim
