#include "hystbench/sim/thermal_drift.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace hystbench::sim {

ThermalDrift::ThermalDrift(const SimulatedActuatorConfig::ThermalDrift& config, double dt_s)
    : config_(config), dt_s_(dt_s), rng_(config.seed) {}

double ThermalDrift::step() noexcept {
  if (!config_.enabled) return 0.0;
  ++samples_;
  if (config_.shape == DriftShape::kSinusoid) {
    const double t = static_cast<double>(samples_) * dt_s_;
    return config_.amplitude_um * std::sin(2.0 * std::numbers::pi * t / config_.period_s);
  }
  const double sigma = config_.random_walk_um_per_sqrt_s * std::sqrt(dt_s_);
  walk_um_ = std::clamp(walk_um_ + sigma * unit_normal_(rng_), -config_.random_walk_limit_um,
                        config_.random_walk_limit_um);
  return walk_um_;
}

void ThermalDrift::reset() noexcept {
  samples_ = 0;
  walk_um_ = 0.0;
  rng_.seed(config_.seed);
  unit_normal_.reset();
}

}  // namespace hystbench::sim
