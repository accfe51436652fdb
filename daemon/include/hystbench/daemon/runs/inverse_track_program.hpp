#pragma once
// Building blocks of a tracking run whose feedforward is a model's inverse, shared by `track`
// and by identify's verification: the model's output range, the open-loop precondition sweep,
// the model simulated through that sweep (so the inverse starts in the state the actuator is
// in), a verification program, and the tracking-error figures of a finished run.
// Units: V in, µm out, s. Control thread only: everything here allocates and may throw; the
// programs it builds run on the loop without allocating.
#include <memory>
#include <nlohmann/json.hpp>
#include <span>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/daemon/loop/output_limiter.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "hystbench/daemon/runs/track_drive.hpp"

namespace hystbench::daemon {

/// Lowest and highest output of a model's major loop [µm].
struct ModelOutputRange {
  double y_bottom = 0.0;
  double y_top = 0.0;
};

/// The model (a copy) relaxed at u_min, driven to u_max and back at sample period dt_s [s].
ModelOutputRange major_loop_range(const compensation::ActuatorModel& model, double u_min,
                                  double u_max, double dt_s);

/// Open-loop ramps u_now -> u_max -> u_min, precondition_s / 2 each [V per sample]; empty for 0.
/// The sweep wipes the hysteresis memory, so the state at its end does not depend on history.
std::vector<double> precondition_sweep(double u_now, double u_min, double u_max,
                                       double precondition_s, double dt_s);

/// Arms the tare of a track drive after a precondition sweep of `sweep_samples`: the output's
/// unpredicted offset is measured on the falling ramp (TareWindow::from), once the turn at u_max
/// has wiped both the actuator's and the model's memory (no tare without a sweep), with readings
/// matched to the outputs they answer less `model_exchange_ticks`.
void arm_tare(TrackDrive& track, std::size_t sweep_samples, std::uint64_t model_exchange_ticks);

/// A copy of `model` configured for dt_s, relaxed at u_start, simulated through `prefix`, its
/// input range narrowed to [u_min, u_max] (or set to it when the model has none): the model an
/// inverse should start from after the prefix.
compensation::ActuatorModel model_after(const compensation::ActuatorModel& model,
                                        std::span<const double> prefix, double u_start,
                                        double u_min, double u_max, double dt_s);
/// As model_after, from `state` (the model configured for the loop's period, in the state the
/// actuator's history left it) instead of relaxed at u_start.
compensation::ActuatorModel model_after(compensation::ActuatorModel state,
                                        std::span<const double> prefix, double u_min, double u_max);

/// identify's verification segment: the standard tracking reference, through the inverse.
struct VerificationSpec {
  /// A triangle (the standard segment) or a sine (a fast one, where dynamics and delay show).
  enum class Reference { kTriangle, kSine };
  Reference reference = Reference::kTriangle;
  double frequency_hz = 1.0;    ///< reference frequency [Hz], > 0
  double periods = 2.0;         ///< >= 1; with 2 or more the first is left out of the figures
  double range_fraction = 0.8;  ///< of the model's major-loop range, (0, 1]
  double precondition_s = 1.0;  ///< sweep before the reference [s], >= 0
  /// Roll-off of the dynamics inversion, as `track` uses it (DynamicsInversion) [Hz]; 0 = default.
  double feedforward_bandwidth_hz = 0.0;
  /// The driver exchange latency the model's delay holds (its identification's) [ticks].
  std::uint64_t model_exchange_ticks = 0;
};

/// A kTrack program (no log: the caller opens one) following spec.reference over
/// spec.range_fraction of the model's range with the model's inverse, preconditioned like
/// `track`. Throws compensation::NotInvertibleError or std::invalid_argument.
std::unique_ptr<RunProgram> make_verification_program(const compensation::ActuatorModel& model,
                                                      const VerificationSpec& spec, double u_now,
                                                      const OutputLimits& limits, double dt_s);

/// Tracking-error figures of a finished track program: rms / max [µm] and % of the reference's
/// span, remaining hysteresis; an empty object when it recorded fewer than 3 samples.
nlohmann::json tracking_error_json(const RunProgram& run);

}  // namespace hystbench::daemon
