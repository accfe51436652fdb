#pragma once
// Feedforward planned over a known reference. A causal or previewed inverse solves each tick for
// itself; at the top of a fast reference the rate-dependent paper's per-sample law (W_i + c_i
// |du/dt|) leaves it no good choice: the falling drive raises the output by its own rate, so
// following the reference right up to the top forces an error after it. Knowing the whole
// reference, plan_drive() chooses every drive sample at once: it minimises the sum of squared
// differences between the model's static output (hysteresis, rate law, creep) and the targets by
// Levenberg-Marquardt on the exact, sparse Jacobian (a play's output depends on the drive of the
// tick it last moved, the rate on this tick's and the last), solved matrix-free by conjugate
// gradients, starting from the previewed inverse's drive. Long references are planned in chunks
// that overlap, each from the state the committed drive leaves.
// Units: drive in the model's input unit, targets and errors in its output unit, s.
// Control thread only: allocates and takes time, in proportion to plan_drive_work() (the time
// per unit: the benchmark plan_drive_10hz).
#include <cstddef>
#include <functional>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"

namespace hystbench::compensation {

struct DrivePlanOptions {
  /// Drive bounds [input unit]; default (min >= max): the model's identification range.
  double input_min = 0.0;
  double input_max = 0.0;
  /// Per-tick changes of the drive beyond this many times the rate-free (modified PI) inverse's
  /// largest over the same targets are penalised; <= 0: no bound. A rate law capped at the
  /// identified max_rate would otherwise invite one-tick jumps (rate beyond the cap is "free" to
  /// the model), which is the model's extrapolation guard, not the stage.
  double max_step_factor = 2.0;
  /// The model holds its rate law at max_rate beyond it. Where its record went beyond
  /// (record_max_rate > max_rate) that is a saturation the record showed, and the plan uses it;
  /// where max_rate is only the record's end, an extrapolation guard, the plan is optimised on
  /// the linear law continued instead, so it never gains from rates the model was not
  /// identified at. Set: hold (true) or continue (false) whatever the model says.
  std::optional<bool> hold_rate_beyond_max;
  /// The previewed inverse's drive is the plan, without iterating, when its rms on the model is
  /// at most this [output unit] (a slow reference: a second of planning would not gain); 0:
  /// always iterate.
  double accept_start_rms = 0.0;
  int iterations = 25;     ///< Levenberg-Marquardt steps per chunk, >= 1
  int cg_iterations = 80;  ///< conjugate-gradient steps per Levenberg-Marquardt step, >= 1
  /// Samples planned together, and how many of the next chunk's they also plan (the end of a
  /// chunk has no future to balance against, so only the first chunk_samples are kept).
  std::size_t chunk_samples = 20000;
  std::size_t overlap_samples = 2000;
  /// Called with the fraction planned (0..1) after each Levenberg-Marquardt step; may be empty.
  std::function<void(double)> progress;
};

struct DrivePlan {
  std::vector<double> u;  ///< one drive sample per target [input unit]
  /// The model's output change per input change when the whole drive shifts, along the plan,
  /// averaged over 5 ms, and at least a tenth of the plan's mean slope (the targets' span over
  /// the drive's) [output unit / input unit]: a target that differs from the planned one by dy
  /// is met to first order by u + dy / gain.
  std::vector<double> gain;
  /// rms of the model's output less the targets [output unit], the model as it is (its rate law
  /// held beyond max_rate): the previewed inverse's drive, and the plan.
  double start_rms = 0.0;
  double rms = 0.0;
};

/// True when plan_drive() plans for this model: a rate-dependent PI hysteresis of a weight law
/// that is not inverted exactly forward in time (for rate-free models, the family's nested one
/// with every rate coefficient zero included, the previewed inverse is already exact where the
/// target is reachable).
bool can_plan_drive(const ActuatorModel& model) noexcept;

/// The work of plan_drive() for `samples` targets in sample-operators, samples x (plays + 2)
/// (the time each takes: bench `plan_drive_10hz`); 0 when can_plan_drive() is false.
double plan_drive_work(const ActuatorModel& model, std::size_t samples) noexcept;

/// The drive that makes `model` (relaxed at u_start, then driven through `prefix`) give the
/// static `targets` (one per sample at the model's sample period; delay and dynamics already
/// inverted by the caller). Throws std::invalid_argument when can_plan_drive() is false, the
/// targets are empty or a value is not finite.
DrivePlan plan_drive(const ActuatorModel& model, double u_start, std::span<const double> prefix,
                     std::span<const double> targets, const DrivePlanOptions& options = {});

/// A plan for the start of a periodic reference continued to `samples`: from its last period
/// on (planned without the future to balance against) each sample repeats the period before,
/// a whole number of periods earlier, linearly interpolated where the period is a fractional
/// number of samples. Right where the model's state repeats with the reference once it has
/// passed through one period (a rate-dependent PI without creep): plan the first period and
/// two more. Throws std::invalid_argument unless 1 < period_samples <= (plan.u.size() - 1) / 2
/// and samples >= its size. rms and start_rms stay those of the part planned.
DrivePlan continue_periodic_plan(DrivePlan plan, double period_samples, std::size_t samples);

}  // namespace hystbench::compensation
