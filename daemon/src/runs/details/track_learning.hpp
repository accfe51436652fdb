#pragma once
// The learner of a `track --learn N` run, on the supervisor thread: takes each trial the loop
// closes (LearningExchange), scores it, lets the guard decide, and offers the next trial's drive
// (compensation::IterativeLearning), or the best trial's drive twice (a period to settle, then the
// last) when the guard stops the learning. Trial 1 plays trial 0's drive again: what differs
// between the two is what does not repeat on the bench (noise, a DAQ's clock, stale readings),
// the floor no learning goes below. The first trial within kFloorReach of it plays its drive
// again, and that pair measures the floor anew, at the error the learning reached; a trial
// within kFloorReach of the floor then stops the learning the same way, and says so. N learned
// trials follow the two. Its result is the run's `learning` object; the drive it keeps is saved for
// replay. Not real-time safe.
#include <array>
#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "hystbench/compensation/error_metrics.hpp"
#include "hystbench/compensation/iterative_learning.hpp"
#include "hystbench/compensation/learning_guard.hpp"
#include "hystbench/daemon/runs/learning_exchange.hpp"
#include "runs/details/learned_drive.hpp"

namespace hystbench::daemon::details {

/// What a learning run is asked for and built with.
struct LearningRequest {
  std::size_t trials = 10;    ///< learned trials after the first (the compensator's)
  double gain = 0.5;          ///< gamma at the start, (0, 20]
  double range_um = 0.0;      ///< the reference's span: errors in % of it
  double frequency_hz = 0.0;  ///< the trial's frequency (the loop rate / P)
  std::string reference;      ///< its kind (sine, triangle, sawtooth, upload)
  std::string signature;      ///< an upload's fingerprint (empty for a built-in one)
  /// A trial's first scored phase: an upload's pass scores its trajectory, not the approach
  /// before it (the learner learns both).
  std::size_t scored_from = 0;
  double rate_hz = 0.0;               ///< the loop rate
  double min_um = 0.0, max_um = 0.0;  ///< the reference's extremes
  /// A drive learned before (P samples) that trial 0 plays instead of the compensator's, and
  /// its name; empty: the compensator's.
  std::vector<double> start_drive;
  /// The compensator's feedforward in the run that learned it (P samples; empty: the drive
  /// plays as saved): the drive moves by how far the compensator's moves from it.
  std::vector<double> start_compensator;
  std::string start_name;
};

/// What a drive of `period_samples` learned for `r` belongs to (saved with it, checked on replay).
LearnedFor learned_for(const LearningRequest& r, std::size_t period_samples);

class TrackLearning {
 public:
  /// A trial within this factor of the floor ends the learning.
  static constexpr double kFloorReach = 1.25;
  /// The floor leaves out the trials' difference's first this many harmonics (the start from
  /// rest settling toward the orbit it repeats), over trials of at least kFloorMinSamples.
  static constexpr std::size_t kFloorSettlingHarmonics = 2;
  static constexpr std::size_t kFloorMinSamples = 100;
  /// The best trial's drive played again after the learning stopped repeats its error while the
  /// replays stay within this factor of it.
  static constexpr double kReplayHeld = 1.5;

  TrackLearning(const compensation::ActuatorModel& model, LearningExchange& exchange,
                LearningRequest request, const compensation::LearningOptions& options);

  /// A trial the learner scored: number, rms and max error [% of range], the gain it was
  /// learned with, what drive it played.
  struct Trial {
    std::uint64_t trial = 0;
    double rms_percent = 0.0, max_percent = 0.0, rms_um = 0.0, max_um = 0.0;
    std::uint64_t max_tick = 0;  ///< the run tick (the log's index) of its largest error
    double gain = 0.0;
    /// "compensator", "saved" (a drive learned before), "learned" or "best" (kept after the
    /// guard stopped)
    std::string drive;
  };

  /// Takes every trial the loop closed since the last call and offers the next drive; returns
  /// the trials scored now (for run.progress).
  std::vector<Trial> poll();
  /// The learning failed (`why`): no more drives are offered, and the result says so.
  void fail(const std::string& why);

  /// The run's `learning` object; the last trial's rms and max [µm] when any was scored.
  nlohmann::json result() const;
  /// A run's (or a stage axis's) figures are its last trial's, the log keeping every period:
  /// writes rms/max [µm and % of range] and the max's tick into `figures`; nothing before any.
  void put_last_trial_figures(nlohmann::json& figures) const;
  /// The drive the run ends with: the best trial's when the guard stopped, else the last one
  /// offered (the drive started from before any); empty before any.
  const std::vector<double>& kept_drive() const noexcept { return kept_; }
  /// The compensator's feedforward over the last trial taken (P samples; empty before any).
  const std::vector<double>& kept_compensator() const noexcept { return c_; }
  /// What the compensator's target took off in the trials [µm], the run's tare given.
  double target_offset(double tare_um) const noexcept {
    return exchange_.target_offset(exchange_.first_tick, tare_um);
  }
  const LearningRequest& request() const noexcept { return request_; }

 private:
  std::optional<Trial> last_trial() const;
  LearningExchange& exchange_;
  LearningRequest request_;
  // The `above_cutoff` object: how a fast trial learned its harmonics above Q, or why not.
  nlohmann::json above_cutoff() const;
  // The `best_replayed` object: the replays of the best trial's drive against its own error.
  nlohmann::json best_replayed() const;

  compensation::IterativeLearning learner_;
  bool mode_in_model_ = false;   ///< the model holds a mode (else the identify's timed one)
  bool cutoff_by_hand_ = false;  ///< learn_cutoff_hz set Q (nothing is learned above it)
  compensation::LearningGuard guard_;
  // Every trial scored, trial 0 first; the guard judges those after it (its trial i is
  // trials_[i + 1]).
  std::vector<Trial> trials_;
  std::vector<double> u_, c_, e_, next_, best_drive_, kept_;
  std::uint64_t best_drive_trial_ = 0;  ///< the trial that played best_drive_
  bool stopped_ = false;
  bool done_ = false;  ///< the last drive was offered
  std::string why_;
  double next_gain_ = 0.0;  ///< the gain the drive offered last was learned with
  std::string next_drive_;  ///< what it is: "learned" or "best"
  double update_ms_sum_ = 0.0, update_ms_max_ = 0.0;
  std::size_t updates_ = 0;
  // The floor: trial 0's error, kept until trial 1 (the same drive) closes; then the rms of
  // their difference over sqrt(2) [µm] (0 before).
  std::vector<double> first_error_;
  double floor_um_ = 0.0;
  double first_floor_um_ = 0.0;  ///< the floor trials 0 and 1 measured
  // The two trials of one drive the floor comes from: 0 and 1, then where a trial reached
  // that floor, it and the repeat of its drive.
  std::array<std::uint64_t, 2> floor_trials_{0, 1};
  bool remeasured() const noexcept { return floor_trials_[0] != 0; }
  // The share of the reference's span [%] of a length [µm] (0 without a span).
  double percent(double um) const noexcept {
    return compensation::percent_of_range(um, request_.range_um);
  }
  // Whether trial n is the repeat of trial 0 (no learning between them).
  bool repeats(std::uint64_t n) const noexcept { return n == 0 && request_.trials > 0; }
  // The trials' rms within their scored phases [µm].
  double scored_rms(const std::vector<double>& e) const noexcept;
  // The trial just taken (u_, e_), scored.
  Trial score(std::uint64_t number, std::uint64_t first_tick) const;
  // The floor from trial 1's error (e_) and trial 0's.
  void measure_floor();
  // The best drive offered next (the guard stopped, or the trial reached the floor); true
  // when it is the last.
  bool stop_on_best(const Trial& t, bool at_floor);
  // The drive of trial `number` (u_) offered again for the next, its error (e_) kept to measure
  // the floor against.
  void offer_repeat(std::uint64_t number);
  // The next drive learned from the trial just taken.
  void learn_next();
};

}  // namespace hystbench::daemon::details
