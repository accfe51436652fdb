#pragma once
// Uniform quantiser of a DAC or ADC: 2^bits codes over [range_min, range_max], step
// (range_max - range_min) / (2^bits - 1); inputs outside the range clamp to its ends.
// Units are the caller's. apply() is real-time safe.
#include "hystbench/sim/simulated_actuator_config.hpp"

namespace hystbench::sim {

class Quantizer {
 public:
  /// Identity (no quantisation, no clamp).
  Quantizer() = default;
  /// The config is taken as given (validate() the whole actuator config first); a disabled
  /// config gives the identity.
  explicit Quantizer(const QuantizationConfig& config);

  /// Nearest code's value; NaN stays NaN.
  double apply(double value) const noexcept;
  /// Distance between neighbouring codes; 0 for the identity.
  double step_size() const noexcept { return step_; }

 private:
  double min_ = 0.0;
  double max_ = 0.0;
  double step_ = 0.0;
};

}  // namespace hystbench::sim
