#pragma once
// What a track or excite run plays, built and checked before anything moves (pure functions,
// no threads; throw CommandError naming the cause). Not real-time safe.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/daemon/runs/upload_store.hpp"
#include "hystbench/sim/signal_generator.hpp"
#include "runs/details/track_request.hpp"

namespace hystbench::daemon::details {

/// A tracking run's reference after the open-loop prefix.
struct TrackReference {
  std::unique_ptr<sim::SignalGenerator> signal;  ///< [µm] against time from the prefix's end
  std::uint64_t samples = 0;                     ///< ticks of the reference part of the run
  std::uint64_t unscored = 0;  ///< its leading ticks left out of the error figures
  double min_um = 0.0, max_um = 0.0;
  double frequency_hz = 0.0;  ///< fundamental of a periodic one (sine, triangle, sawtooth), else 0
  /// A trajectory played over and over (learned): ticks per pass (its approach and itself);
  /// 0 otherwise.
  std::size_t pass_samples = 0;
  std::size_t pass_approach = 0;   ///< its leading ticks, the approach (unscored in every pass)
  std::size_t lead_in_passes = 1;  ///< the unscored passes ahead of the first trial, at most
  /// A trajectory's fundamental [Hz] estimated from its reversals (a raster's line rate); 0 for
  /// a built-in one.
  double content_hz = 0.0;
  /// A trajectory's fingerprint (its resampled values, 16 hex digits); empty for a built-in one.
  std::string signature;
  nlohmann::json header;  ///< keys of the run log header's "run" object
  nlohmann::json reply;   ///< the start reply's "reference" object
};

/// The actuator's output range and how fast the reference may move [µm, µm/s].
struct ReferenceLimits {
  double y_bottom = 0.0, y_top = 0.0;
  double slew_um_per_s = 0.0;  ///< the output slew limit through the range's mean gain
  double rate_hz = 0.0;        ///< the loop rate
};

/// A built-in periodic reference from a track request's keys: its kind, frequency, periods or
/// duration, range_fraction or min_um/max_um (refused beyond the actuator's range). The first
/// period is unscored when the run has at least two.
/// frequency_hz and periods > 0 take the place of the request's (a learning run's trials).
TrackReference builtin_reference(const BuiltinReferenceRequest& request,
                                 const ReferenceLimits& limits, double frequency_hz = 0.0,
                                 double periods = 0.0);

/// A user's trajectory, resampled to the loop rate, after an approach of approach_s (at least
/// long enough for the slew limit) from y_start to its first value, which is unscored. Refused
/// (out_of_range, slew_limit) with the first offending sample named, in words and as
/// {"sample": k, "t_s": t} details.
/// With learned_trials (a learning run, track --learn N): played in passes of pass_samples
/// ticks, each an approach then the trajectory, as many as learning_periods(N) asks; the first
/// approaches from y_start and is unscored whole (the start-up), each later one from the
/// trajectory's end, in as many ticks as the first. lead_in_max_s > 0: as many passes more,
/// unscored, as fill that long after the first (a learned drive's longest lead-in,
/// lead_in_passes in all).
TrackReference uploaded_reference(const Upload& upload, const ReferenceLimits& limits,
                                  double y_start, double approach_s,
                                  std::optional<std::size_t> learned_trials = std::nullopt,
                                  double lead_in_max_s = 0.0);

/// How many periods (passes) a learning run over `trials` trials of frequency_hz [Hz] plays at
/// most: the start-up, the first trial and its repeat (the bench's floor), the learned ones, and
/// time for the learner's update before each (a period that begins before its drive is ready
/// plays the last one again). The run ends after its last trial.
double learning_periods(std::size_t trials, double frequency_hz);

/// The whole periods of frequency_hz [Hz] that fill seconds [s] (at least one).
std::size_t periods_filling(double seconds, double frequency_hz);

/// A user's drive resampled to the loop period dt_s, checked against the output range and the
/// slew limit in the same way [V].
std::vector<double> checked_drive(const Upload& upload, double u_min, double u_max,
                                  double slew_v_per_s, double dt_s);

}  // namespace hystbench::daemon::details
