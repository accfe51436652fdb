#pragma once
// Classical Prandtl-Ishlinskii model: y = offset + sum_i w_i * H_{r_i}[u], 0 = r_0 < r_1 < ... .
// r_0 may be > 0 (pure backlash first segment) but such a model is not invertible.
// Real-time safe step()/peek(); vectorisable inner loop (structure of arrays).
#include <span>
#include <vector>

#include "hystbench/compensation/hysteresis_model.hpp"

namespace hystbench::compensation {

struct PiParameters {
  std::vector<double> thresholds;  ///< r_i >= 0, strictly increasing [input unit]
  std::vector<double> weights;     ///< w_i [output unit / input unit]
  double offset = 0.0;             ///< [output unit]
};

/// n thresholds uniformly spaced on [0, r_max): r_i = i * r_max / n.
std::vector<double> uniform_thresholds(std::size_t n, double r_max);

class PiModel final : public HysteresisModel {
 public:
  /// Throws std::invalid_argument naming the field (sizes, NaN, non-increasing thresholds).
  explicit PiModel(PiParameters p);

  ModelKind kind() const noexcept override { return ModelKind::kPi; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  void reset(double u0) noexcept override;
  std::size_t operator_count() const noexcept override { return p_.thresholds.size(); }
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const PiParameters& parameters() const noexcept { return p_; }
  /// Play outputs (state), one per threshold.
  std::span<const double> state() const noexcept { return state_; }
  /// Writable play outputs, for composite models that evaluate the plays themselves.
  std::span<double> mutable_state() noexcept { return state_; }
  /// Sets the play outputs; sizes must match (throws std::invalid_argument otherwise).
  void set_state(std::span<const double> play_outputs);

  /// Sum of weights times plays without the offset, for the given play state.
  double weighted_sum(std::span<const double> play_outputs) const noexcept;

 private:
  PiParameters p_;
  std::vector<double> state_;
};

/// Parameters of the analytic inverse (Kuhnen; rate-dependent paper eq. 13):
///   r'_i = sum_{j<=i} w_j (r_i - r_j),  w'_0 = 1/w_0,  w'_i = -w_i / (W_i W_{i-1}).
/// The inverse acts on (y - offset) and has offset 0. Throws NotInvertibleError.
PiParameters inverse_parameters(const PiParameters& model);
/// Inverse play state consistent with a model play state p:
///   p'_i = W_i p_i + sum_{j>i} w_j p_j  (W_i the cumulative weight).
std::vector<double> inverse_state(const PiParameters& model, std::span<const double> play_outputs);

}  // namespace hystbench::compensation
