#pragma once
// A track request parsed once, at the edge, into what the run builders take: every key read,
// typed and checked against the bench (the loop rate's ranges, the active model), defaults
// filled in. Errors are CommandError naming the key (bad_params) or the missing model
// (no_model). Not real-time safe.
#include <cstddef>
#include <optional>
#include <string>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/sim/signal_generator.hpp"
#include "runs/details/feedback_design.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// A built-in periodic reference's keys (a track without reference_upload). Every value, and its
/// default, comes from the request's table (hystbench/common/run_requests.hpp:
/// kTrackBuiltinParams).
struct BuiltinReferenceRequest {
  std::string name;  ///< reference: sine, triangle, sawtooth, chirp, ...
  sim::SignalKind kind = sim::SignalKind::kTriangle;
  double frequency_hz = 0.0;  ///< in [1e-3, loop rate / 20]
  double periods = 0.0;
  double duration_s = 0.0;      ///< 0: periods / frequency_hz
  double range_fraction = 0.0;  ///< of the actuator's range, centred in it
  /// The reference's bottom and top in place of range_fraction [µm]; either may be given.
  std::optional<double> min_um, max_um;
  /// step: how long each move takes [s] (a minimum-jerk curve): three periods of the stage's
  /// first mode (its measured responses', else the model's), at least four ticks.
  double rise_s = 0.0;
};

/// A learning run's keys: trials > 0 learns over that many trials; a learned drive's name
/// starts from (or, with no trials, replays) that drive. Defaults: the request's table.
struct LearningKeys {
  std::size_t trials = 0;
  /// Of the error corrected per trial (half by default, so a plant whose local slope is half
  /// the model's still converges, and one of twice it is at the edge).
  double gain = 0.0;
  double cutoff_hz = 0.0;              ///< the learner's low-pass; 0: its default
  std::optional<std::string> learned;  ///< a saved drive's name
  /// With `learned`, a sine's, triangle's or sawtooth's: the longest lead-in [s] while the
  /// actuator's offset moves toward the one the drive was learned at; 0: its minimum.
  double lead_in_max_s = 0.0;
  bool any() const { return trials > 0 || learned.has_value(); }
};

struct TrackRequest {
  /// none, inverse, inverse_multiplicative, inverse+pid or pid; inverse with a model, else none.
  std::string compensator;
  compensation::CompensatorKind compensator_kind = compensation::CompensatorKind::kNone;
  std::string reference_upload;       ///< a complete reference upload's name; empty: built-in
  BuiltinReferenceRequest reference;  ///< with reference_upload empty
  double approach_s = 0.0;            ///< an upload's approach from rest [s]
  double precondition_s = 0.0;        ///< the open-loop sweep before the reference [s]
  FeedbackGainsRequest gains;
  LearningKeys learning;
};

/// The request (checked against track's parameters) over the bench's defaults.
TrackRequest parse_track_request(const RequestParams& request, const RunContext& ctx);

}  // namespace hystbench::daemon::details
