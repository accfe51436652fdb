#pragma once
// Asymmetric PI built from coupled-play (CP) operators (coupled-play paper, eq. 3-4).
// A CP operator is a play whose half-width depends on direction and input level:
//   rising  (u >= u_prev): z = max(z_prev, u - (u >= rc ? r : rc))
//   falling (u <  u_prev): z = min(z_prev, u + (u <= -rb ? ra : rb))
// (the paper's eq. 3 with its sign typos read this way: the falling branch lies above the input).
// y = offset + sum_i w_i z_i. No closed-form inverse: use NumericInverse.
// Real-time safe step()/peek().
#include <vector>

#include "hystbench/compensation/hysteresis_model.hpp"

namespace hystbench::compensation {

struct CoupledPlayParameters {
  std::vector<double> r, ra, rb, rc;  ///< per operator, each >= 0 [input unit]
  std::vector<double> weights;        ///< [output unit / input unit]
  double offset = 0.0;                ///< [output unit]
};

class CoupledPlayPiModel final : public HysteresisModel {
 public:
  explicit CoupledPlayPiModel(CoupledPlayParameters p);

  ModelKind kind() const noexcept override { return ModelKind::kCoupledPlayPi; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  void reset(double u0) noexcept override;
  std::size_t operator_count() const noexcept override { return p_.weights.size(); }
  /// Requires rc >= r and ra <= rb per operator (monotone branches) and cumulative weights > 0,
  /// so the numeric inverse is unique.
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const CoupledPlayParameters& parameters() const noexcept { return p_; }

  /// Output of one CP operator for input u given its previous output and the previous input.
  static double operator_output(double u, double u_prev, double z_prev, double r, double ra,
                                double rb, double rc) noexcept;

 private:
  CoupledPlayParameters p_;
  std::vector<double> z_;
  double u_prev_ = 0.0;
};

}  // namespace hystbench::compensation
