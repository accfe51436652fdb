#pragma once
// The bench's compensator: feedforward from a model inverse plus optional incremental PID.
//   none                  u = (y_ref - offset) / gain               (linear map, no model)
//   inverse               u = inverse(y_ref)
//   inverse_multiplicative u = inverse-multiplicative structure(y_ref)
//   inverse_pid           u = inverse(y_ref) + pid(e)
//   pid                   u = (y_ref - offset) / gain + pid(e)     (the linear map and feedback)
// e is the error of the last completed tick, y_ref(k-1) - y(k-1), so a reference that moves
// does not show up as error. `pid` starts from the linear map's drive, as `none`: an integral
// loop alone, slow enough for the actuator's lags, would trail a 1 Hz reference by more than
// the hysteresis it removes. The linear map acts on the feedforward target (the reference less
// the tare). step() is real-time safe.
#include <memory>
#include <optional>
#include <span>
#include <string_view>

#include "hystbench/compensation/inverse_model.hpp"
#include "hystbench/compensation/pid_controller.hpp"

namespace hystbench::compensation {

enum class CompensatorKind { kNone, kInverse, kInverseMultiplicative, kInversePid, kPid };

/// "none", "inverse", "inverse_multiplicative", "inverse+pid", "pid".
std::string_view to_string(CompensatorKind kind) noexcept;
std::optional<CompensatorKind> compensator_kind_from_string(std::string_view name) noexcept;
bool needs_model(CompensatorKind kind) noexcept;
bool uses_feedback(CompensatorKind kind) noexcept;

/// Linear map used by `none`: y = offset + gain * u.
struct LinearMap {
  double gain = 1.0;    ///< [output unit / input unit], > 0
  double offset = 0.0;  ///< [output unit]
};

struct CompensatorOutput {
  double u_ff = 0.0;                ///< feedforward [input unit]
  double u_fb = 0.0;                ///< feedback [input unit]
  double u = 0.0;                   ///< sum, before the output limits
  bool feedback_saturated = false;  ///< u_fb at the PID's clamp [u_fb_min, u_fb_max]
};

class Compensator {
 public:
  /// `inverse` is required for the inverse kinds, `pid` for the PID kinds; throws
  /// std::invalid_argument naming what is missing.
  Compensator(CompensatorKind kind, std::unique_ptr<InverseModel> inverse,
              std::optional<PidController> pid, LinearMap linear);
  /// A copy in the same state (the inverse cloned): to play ahead what this one would do.
  Compensator(const Compensator& other);
  Compensator& operator=(const Compensator&) = delete;
  Compensator(Compensator&&) noexcept = default;
  Compensator& operator=(Compensator&&) noexcept = default;

  /// y_measured is the measurement of the previous tick (NaN before the first one).
  CompensatorOutput step(double y_ref, double y_measured) noexcept {
    return step(y_ref, y_measured, y_ref);
  }
  /// As above, the feedforward inverting `ff_target` instead of y_ref: the static target a
  /// DynamicsInversion computed from the previewed reference (feedback still acts on y_ref).
  CompensatorOutput step(double y_ref, double y_measured, double ff_target) noexcept {
    return step(y_ref, y_measured, std::span<const double>(&ff_target, 1));
  }
  /// As above with the feedforward targets of this tick and the ticks ahead (ff_targets[0] is
  /// this tick's; at most preview_samples() values, at least one): see InverseModel.
  CompensatorOutput step(double y_ref, double y_measured,
                         std::span<const double> ff_targets) noexcept;
  /// How many feedforward targets ahead the inverse can use (0: only this tick's).
  std::size_t preview_samples() const noexcept {
    return inverse_ ? inverse_->preview_samples() : 0;
  }
  /// The stage after the compensator clamped the output: +1 high, -1 low, 0 none.
  void notify_saturation(int direction) noexcept;
  /// Starts from a relaxed actuator at input u0.
  void reset(double u0) noexcept;
  CompensatorKind kind() const noexcept { return kind_; }

 private:
  CompensatorKind kind_;
  std::unique_ptr<InverseModel> inverse_;
  std::optional<PidController> pid_;
  LinearMap linear_;
  double y_ref_prev_ = 0.0;
  bool have_prev_ = false;
};

}  // namespace hystbench::compensation
