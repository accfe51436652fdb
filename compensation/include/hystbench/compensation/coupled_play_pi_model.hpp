#pragma once
// Asymmetric PI built from coupled-play (CP) operators (coupled-play paper, eq. 3-4).
// A CP operator is a play whose half-width depends on direction and input level:
//   rising  (u >= u_prev): z = max(z_prev, u - (u >= rc ? r : rc))
//   falling (u <  u_prev): z = min(z_prev, u + (u <= -rb ? ra : rb))
// (the paper's eq. 3 with its sign typos read this way: the falling branch lies above the input).
// v = offset + sum_i w_i z_i. No closed-form inverse: use NumericInverse.
// Optional output stage, as Kuhnen's modified PI puts after plain plays: y = center + S[v -
// center], S a dead-zone superposition (dead_zone.hpp). It forms a saturating or asymmetric output
// map, which the operators' input-level widths cannot; with no dead zones y = v (the paper's
// model). Real-time safe step()/peek().
#include <vector>

#include "hystbench/compensation/dead_zone.hpp"
#include "hystbench/compensation/hysteresis_model.hpp"

namespace hystbench::compensation {

struct CoupledPlayParameters {
  std::vector<double> r, ra, rb, rc;  ///< per operator, each >= 0 [input unit]
  std::vector<double> weights;        ///< [output unit / input unit]
  double offset = 0.0;                ///< [output unit]
  /// Output dead zones (forward operator S); no thresholds = none (identity).
  DeadZoneParameters dead_zone;
  double center = 0.0;  ///< [output unit] the level S acts about (with dead zones only)

  bool has_dead_zones() const noexcept { return !dead_zone.thresholds.empty(); }
};

class CoupledPlayPiModel final : public HysteresisModel {
 public:
  explicit CoupledPlayPiModel(CoupledPlayParameters p);

  ModelKind kind() const noexcept override { return ModelKind::kCoupledPlayPi; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  void reset(double u0) noexcept override;
  std::size_t operator_count() const noexcept override {
    return p_.weights.size() + p_.dead_zone.thresholds.size();
  }
  /// Requires rc >= r and ra <= rb per operator (monotone branches), a weight >= 0 on every
  /// operator that jumps (rc > r or ra < rb), cumulative weights > 0 and an invertible
  /// dead-zone stage, so the output never falls as the input rises and the inverse is unique.
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const CoupledPlayParameters& parameters() const noexcept { return p_; }

  /// Output of one CP operator for input u given its previous output and the previous input.
  static double operator_output(double u, double u_prev, double z_prev, double r, double ra,
                                double rb, double rc) noexcept;

 private:
  double output(double v) const noexcept { return p_.center + dz_.apply(v - p_.center); }

  CoupledPlayParameters p_;
  DeadZoneSuperposition dz_;  ///< identity without dead zones
  std::vector<double> z_;
  double u_prev_ = 0.0;
};

}  // namespace hystbench::compensation
