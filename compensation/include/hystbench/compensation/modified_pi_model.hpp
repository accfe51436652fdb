#pragma once
// Modified PI (Kuhnen): z = center + S[ PI(u) - center ], S a superposition of 2m+1 one-sided
// dead-zone operators (see dead_zone.hpp). `center` is a fixed output level (the middle of the
// identification data's output range) about which the dead zones act; it is not a fit parameter.
// Real-time safe step()/peek().
#include "hystbench/compensation/dead_zone.hpp"
#include "hystbench/compensation/pi_model.hpp"

namespace hystbench::compensation {

struct ModifiedPiParameters {
  PiParameters play;
  DeadZoneParameters dead_zone;
  double center = 0.0;  ///< [output unit]
};

class ModifiedPiModel final : public HysteresisModel {
 public:
  explicit ModifiedPiModel(ModifiedPiParameters p);

  ModelKind kind() const noexcept override { return ModelKind::kModifiedPi; }
  double step(double u) noexcept override;
  double peek(double u) const noexcept override;
  void reset(double u0) noexcept override { pi_.reset(u0); }
  std::size_t operator_count() const noexcept override;
  Invertibility invertibility() const override;
  std::unique_ptr<HysteresisModel> clone() const override;

  const ModifiedPiParameters& parameters() const noexcept { return p_; }
  const PiModel& play_part() const noexcept { return pi_; }
  PiModel& play_part() noexcept { return pi_; }
  const DeadZoneSuperposition& dead_zone_part() const noexcept { return dz_; }

 private:
  ModifiedPiParameters p_;
  PiModel pi_;
  DeadZoneSuperposition dz_;
};

}  // namespace hystbench::compensation
