#pragma once
// The check a model passes before it is written (identify's extension, `diagnose
// --save-extended`): its input range an interval, its hysteresis invertible, and its inverse
// existing over that range, shown by driving the model's static part (hysteresis and creep)
// with its own inverse along a slow triangle over 5-95 % of its output range. A model that
// passes may still describe the actuator badly: the bench's verification judges that. Its
// dynamics are stable by construction (ActuatorModel refuses a mode with f_n or zeta <= 0, whose
// exact discretisation is stable at every sample period), as its delay and creep are sound.
// Allocates and simulates (tens of ms for a 20 x 20 plane at 10 kHz): not for the real-time path.
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/compensation/actuator_model.hpp"

namespace hystbench::compensation {

struct ModelCheck {
  bool passed = true;
  /// The part that failed: "input_range", "hysteresis", "inverse"; empty when passed.
  std::string part;
  /// A sentence for the user naming the cause; empty when passed.
  std::string reason;
  /// The static model driven by its inverse along the triangle, the second period: rms and max
  /// of (model output - reference) in % of the model's output range (NaN when not reached).
  double inverse_rms_percent = NAN;
  double inverse_max_percent = NAN;

  /// Limits on the triangle: an inverse that exists tracks its own model to a small fraction
  /// of these (its solver's tolerance, its saturation at the input range).
  static constexpr double kMaxRmsPercent = 0.5;
  static constexpr double kMaxMaxPercent = 2.0;
};

/// Checks `model` at sample period dt_s (> 0 [s], the bench's). Never throws for a bad model:
/// the result names the failure. Throws std::invalid_argument for dt_s not finite and > 0.
ModelCheck check_model(const ActuatorModel& model, double dt_s);

/// {"passed", and where known "part", "reason", "inverse_rms_percent", "inverse_max_percent"}:
/// no key empty or NaN.
nlohmann::json to_json(const ModelCheck& check);

/// "passed (its inverse tracks it at 0.01 % rms)" or "failed: <reason>".
std::string describe(const ModelCheck& check);

}  // namespace hystbench::compensation
