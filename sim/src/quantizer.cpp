#include "hystbench/sim/quantizer.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::sim {

Quantizer::Quantizer(const QuantizationConfig& config) {
  if (!config.enabled) return;
  min_ = config.range_min;
  max_ = config.range_max;
  step_ = (max_ - min_) / (std::ldexp(1.0, config.bits) - 1.0);
}

double Quantizer::apply(double value) const noexcept {
  if (step_ == 0.0 || std::isnan(value)) return value;
  const double code = std::round((std::clamp(value, min_, max_) - min_) / step_);
  return min_ + code * step_;
}

}  // namespace hystbench::sim
