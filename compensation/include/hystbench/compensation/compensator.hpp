#pragma once
// The bench's compensator: feedforward from a model inverse (or the linear map), and for the
// feedback kinds a loop (feedback_controller.hpp) whose output v corrects the feedforward's
// target, so that the correction passes the same inverse:
//   none                   u = (target - offset) / gain               (linear map, no model)
//   inverse                u = inverse(target)
//   inverse_multiplicative u = inverse-multiplicative structure(target)
//   inverse_pid            u = inverse(target + v),      v = C[y_ref - y]
//   pid                    u = (target + v - offset) / gain
// Through the inverse the loop sees the actuator over the model (near 1 where the model holds
// the actuator's local slope), not the actuator's slope itself, which a hysteresis loop moves by
// a factor of two along its branches. An inverse solved each tick at its own drive's rate (a
// rate law) is too sensitive to its target for that: there the correction goes through the
// linear map, u = inverse(target) + v / gain (FeedbackPath::kLinearMap). u_ff is the feedforward
// alone (a second copy of the inverse, stepped with the target only), u_fb = u - u_ff: a learned
// drive that replaces u_ff keeps the feedback's share. The error is that of the last completed
// tick, y_ref(k-1) - y(k-1) (a moving reference does not show up as error); y_ref NaN holds v.
// Anti-windup: v's integral stops while the drive sits at a bound of its range (set_drive_range)
// or a later stage clamps it (notify_saturation). step() is real-time safe.
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string_view>
#include <vector>

#include "hystbench/compensation/feedback_controller.hpp"
#include "hystbench/compensation/inverse_model.hpp"

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

/// Where the feedback's target correction v enters the drive.
enum class FeedbackPath { kInverse, kLinearMap };

struct CompensatorOutput {
  double u_ff = 0.0;                ///< feedforward [input unit]
  double u_fb = 0.0;                ///< the feedback's share of u [input unit]
  double u = 0.0;                   ///< the drive, before the output limits
  double v = 0.0;                   ///< the feedback's target correction [output unit]
  bool feedback_saturated = false;  ///< v's PID at its clamp
};

class Compensator {
 public:
  /// `inverse` is required for the inverse kinds, `feedback` for the feedback kinds; throws
  /// std::invalid_argument naming what is missing. Allocates the second inverse and the
  /// targets' buffer.
  Compensator(CompensatorKind kind, std::unique_ptr<InverseModel> inverse,
              std::optional<FeedbackController> feedback, LinearMap linear,
              FeedbackPath path = FeedbackPath::kInverse);
  /// A copy in the same state (the inverses cloned): to play ahead what this one would do.
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
  /// The drive's range [input unit]: v's integral stops while the drive sits at a bound.
  void set_drive_range(double u_min, double u_max) noexcept {
    drive_min_ = u_min;
    drive_max_ = u_max;
  }
  /// Starts from a relaxed actuator at input u0.
  void reset(double u0) noexcept;
  /// The feedback's resonators from rest (FeedbackController::restart_harmonics()); none: nothing.
  void restart_harmonics() noexcept {
    if (feedback_) feedback_->restart_harmonics();
  }
  CompensatorKind kind() const noexcept { return kind_; }
  FeedbackPath feedback_path() const noexcept { return path_; }
  /// The feedback loop (null for a kind without one).
  const FeedbackController* feedback() const noexcept { return feedback_ ? &*feedback_ : nullptr; }

 private:
  double linear_drive(double target) const noexcept {
    return (target - linear_.offset) / linear_.gain;
  }
  double inverse_drive(InverseModel& inverse, std::span<const double> targets) noexcept {
    return targets.size() > 1 ? inverse.step_previewed(targets) : inverse.step(targets.front());
  }

  CompensatorKind kind_;
  std::unique_ptr<InverseModel> inverse_;      // the drive: target + v
  std::unique_ptr<InverseModel> feedforward_;  // the feedforward alone (feedback kinds)
  std::optional<FeedbackController> feedback_;
  LinearMap linear_;
  FeedbackPath path_ = FeedbackPath::kInverse;
  std::vector<double> shifted_;  // the targets + v
  double drive_min_ = -std::numeric_limits<double>::infinity();
  double drive_max_ = std::numeric_limits<double>::infinity();
  int at_bound_ = 0;  // the drive at a bound of its range: +1 high, -1 low
  double y_ref_prev_ = 0.0;
  bool have_prev_ = false;
};

}  // namespace hystbench::compensation
