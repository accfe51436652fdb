#pragma once
// The hand-over between the loop, which plays a learning run's trials, and the learner, which
// computes each next trial's drive off the loop thread. A trial is one period of the reference,
// P samples from first_tick on: the first (trial 0) plays the compensator's own drive, or a drive
// learned before (start_from); each later one the learned feedforward the learner made ready before
// the period began. A period that begins with no new drive ready plays the last one again and is
// not a trial (stale_periods). Every buffer is allocated before the run; the loop's side is
// real-time safe (no allocation, no locks: atomics only).
#include <array>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

namespace hystbench::daemon {

/// How a drive learned before plays its lead-in when the actuator's output offset is not the one
/// it was learned at (creep of an actuator that rested, or that has run for a long time since):
/// the drive moves to meet that offset through the model, whose shape of the move is the model's,
/// so the lead-in goes on while the offset moves toward the learned one, following it.
struct LearningLeadIn {
  /// The offset the drive was learned at [output unit]; NaN: not known, no longer lead-in.
  double learned_offset = std::numeric_limits<double>::quiet_NaN();
  /// The lead-in ends once the offset (the tare and what it followed) is within this of the
  /// learned one [output unit, > 0].
  double tolerance = 0.0;
  /// It follows the offset every this many periods (the first of them, the start from rest, not;
  /// 0: never longer than its minimum).
  std::size_t follow_periods = 0;
  /// ... and ends when, at the pace the offset came closer over the last this many follow
  /// steps, it would not come within the tolerance before the longest lead-in.
  std::size_t stall_steps = 50;
  /// Within the tolerance, the lead-in also waits for a follow step whose mean error is within
  /// this [output unit; 0: it does not]: the offset the drive then plays at is the one the
  /// actuator shows with it, not the tare's estimate (the actuator answers a move of the target
  /// by the model's gain there, not exactly by the move). It waits at most settle_steps steps.
  double settled = 0.0;
  std::size_t settle_steps = 3;
};

struct LearningExchange {
  /// P samples >= 4, the run tick of trial 0's first sample, and how many periods before it a
  /// drive learned before plays as its lead-in (>= 1; the run leaves them unscored). With
  /// follow_offset(), first_tick and lead_in_periods are the latest and the longest.
  LearningExchange(std::size_t period_samples, std::uint64_t first_tick,
                   std::size_t lead_in_periods = 1);

  const std::size_t period;
  const std::uint64_t first_tick;
  const std::size_t lead_in_periods;

  /// Before the run: the lead-in plays at least `min_periods` (<= lead_in_periods), and longer
  /// as `lead_in` says, up to lead_in_periods.
  void follow_offset(std::size_t min_periods, const LearningLeadIn& lead_in) noexcept;
  /// The lead-in's end decided by every axis of a stage together (loop thread only): an axis's
  /// lead-in ends only at a period where every axis's would, so that their trial 0 begins at
  /// one tick. An axis whose offset was within its tolerance at once would otherwise be
  /// scored while another still followed its own, its creep meanwhile left unfollowed.
  struct LeadInTogether {
    std::size_t axes = 0;    ///< the axes that decide (each exchange given this)
    std::uint64_t tick = 0;  ///< the period start the count is of
    std::size_t ending = 0;  ///< the axes whose lead-in would end there
  };
  /// Before the run: decide with the others through `together` (outlives the run).
  void decide_together(LeadInTogether* together) noexcept { together_ = together; }
  /// Why the lead-in ended where it did: its minimum, with no following (none asked for or the
  /// learned offset not known); the offset within the tolerance (at once, or followed there,
  /// and settled as LearningLeadIn::settled asks); followed, it would not get there before the
  /// longest; the longest.
  enum class LeadInEnd { kMinimum, kOffsetReached, kOffsetStalled, kLongest };
  /// The tick trial 0 begins at: first_tick, or earlier where the lead-in ended early (the loop
  /// decides it, a period ahead).
  std::uint64_t first_scored_tick() const noexcept { return start_; }
  /// The earliest it can be (the minimum lead-in).
  std::uint64_t earliest_first_tick() const noexcept { return lead_start_ + min_periods_ * period; }
  /// The periods the lead-in played (after the run), why it ended there, and the offset it
  /// followed beyond the tare [output unit].
  std::size_t lead_in_played() const noexcept {
    return static_cast<std::size_t>((start_ - lead_start_) / period);
  }
  LeadInEnd lead_in_end() const noexcept { return end_; }
  double lead_in_followed() const noexcept { return followed_; }

  // ---- loop side (loop thread only) ----
  /// The phase j in [0, P) of tick k >= first_tick; at j = 0 takes the drive made ready (if any)
  /// and starts recording the trial it plays.
  std::size_t begin_tick(std::uint64_t k) noexcept;
  /// True when the period plays a learned drive: u_ff holds the compensator's feedforward at
  /// phase j on entry [input unit] and the drive's sample on return. A drive learned before
  /// (start_from) moves by how far the compensator's moved from its own in the run that learned
  /// it (the output offset the run measured, through the model's inverse): from `twin` when it
  /// is finite (the compensator's twin at this tick, fed the targets at the offset the drive was
  /// learned at: TrackDrive::learned_twin), else from the feedforward start_from was given.
  bool learned(std::size_t j, double& u_ff,
               double twin = std::numeric_limits<double>::quiet_NaN()) const noexcept;
  /// Before first_tick: as learned() for tick k, true when a drive learned before plays the
  /// lead_in_periods before trial 0 too, so that trial 0 follows its own drive as a learned
  /// trial follows the one before.
  bool lead_in(std::uint64_t k, double& u_ff,
               double twin = std::numeric_limits<double>::quiet_NaN()) const noexcept;
  /// The error (reference - reading) of lead-in tick k, `tare` the run's: its last period (the
  /// second half of a single one) measures the output offset the drive learned before now plays
  /// at; a longer lead-in follows the offset, and each period's first tick decides whether the
  /// period is the lead-in's last.
  void lead_in_error(std::uint64_t k, double error, double tare) noexcept;
  /// That offset [output unit] (0 without a lead-in).
  double lead_in_offset() const noexcept {
    return lead_in_samples_ > 0 ? -lead_in_error_sum_ / static_cast<double>(lead_in_samples_) : 0.0;
  }
  /// What the compensator's target takes off at tick k [output unit]: the run's tare (the
  /// offset measured on the precondition sweep), and with a drive learned before, from trial 0
  /// on, the offset its lead-in measured too; the drive moves with the compensator.
  double target_offset(std::uint64_t k, double tare) const noexcept {
    return tare + followed_ + (started_from_ != 0 && k >= start_ ? lead_in_offset() : 0.0);
  }
  /// Records the feedforward played, the compensator's own and the error (reference -
  /// reading) at phase j; at the period's last sample closes the trial. True when that trial
  /// was the last: the run ends.
  bool end_tick(std::size_t j, double u_ff, double u_compensator, double error) noexcept;
  /// True at a period's start when the learner owes a drive for it (a trial was handed over
  /// and nothing came back yet): on the simulated clock the loop waits for it.
  bool owed(std::uint64_t k) const noexcept;

  // ---- learner side ----
  /// Before the run is handed to the loop: trial 0 plays `drive` (P samples, a drive learned
  /// before) instead of the compensator's, moved by the compensator's feedforward less
  /// `compensator` (P samples: the compensator's in the run that learned it; empty: not
  /// moved); `last`: the run ends after it. False for another length, or a second call.
  bool start_from(const std::vector<double>& drive, const std::vector<double>& compensator,
                  bool last);
  /// Takes the oldest complete trial not yet taken: copies its drive, the compensator's
  /// feedforward and its error into u, c and e (P samples each), its number into trial and,
  /// where given, the run tick of its first sample into first_tick. False when there is none.
  bool take_trial(std::vector<double>& u, std::vector<double>& c, std::vector<double>& e,
                  std::uint64_t& trial, std::uint64_t* first_tick = nullptr);
  /// Makes `drive` (P samples) the next trial's; `last`: the run ends after it. False when the
  /// loop has not taken the one made ready before (call again after the next trial).
  bool offer(const std::vector<double>& drive, bool last) noexcept;
  /// The learner offers no more drives (it failed): the loop stops waiting for one and plays
  /// the last drive it took to the run's end.
  void give_up() noexcept { final_offered_.store(true, std::memory_order_release); }

  std::uint64_t trials_played() const noexcept { return played_.load(std::memory_order_acquire); }
  std::uint64_t stale_periods() const noexcept { return stale_.load(std::memory_order_acquire); }

 private:
  enum Slot : int { kFree = 0, kWriting = 1, kFull = 2, kReading = 3 };
  std::array<std::vector<double>, 2> drive_;
  std::array<std::vector<double>, 2> rec_u_, rec_c_, rec_e_;
  std::vector<double> started_compensator_;  // start_from's compensator (empty: not moved)
  std::array<std::atomic<int>, 2> slot_{};
  std::array<std::atomic<std::uint64_t>, 2> slot_trial_{};
  std::array<std::atomic<std::uint64_t>, 2> slot_tick_{};  // each trial's first run tick
  std::atomic<int> ready_{-1};                             // drive_ index made ready, -1 = none
  std::atomic<bool> ready_last_{false};
  std::atomic<std::uint64_t> played_{0};   // trials closed by the loop
  std::atomic<std::uint64_t> taken_{0};    // trials taken by the learner
  std::atomic<std::uint64_t> offered_{0};  // drives made ready by the learner
  std::atomic<std::uint64_t> stale_{0};
  std::atomic<bool> final_offered_{false};
  std::uint64_t started_from_ = 0;  // 1 when trial 0 plays a drive given before the run
  // loop only
  void start_recording(std::uint64_t trial, std::uint64_t k) noexcept;
  int playing_ = -1;
  bool playing_started_ = false;  // the period plays the drive start_from gave
  bool last_ = false;
  int rec_slot_ = -1;
  std::uint64_t rec_tick_ = 0;  // the recorded trial's first tick
  std::uint64_t trial_ = 0;
  double lead_in_error_sum_ = 0.0;
  std::uint64_t lead_in_samples_ = 0;
  // The lead-in (loop only during the run).
  void decide_lead_in(std::uint64_t k, std::uint64_t begun, double tare) noexcept;
  // How far the offset the target takes off is from the one the drive was learned at.
  double gap(double tare) const noexcept {
    return std::abs(tare + followed_ - follow_.learned_offset);
  }
  std::uint64_t lead_start_ = 0;  // its first tick
  std::uint64_t start_ = 0;       // trial 0's first tick
  std::size_t min_periods_ = 1;
  LearningLeadIn follow_{};
  bool decided_ = false;
  std::uint64_t window_ = 0;  // the last period's samples that measure the offset
  LeadInEnd end_ = LeadInEnd::kLongest;
  double followed_ = 0.0;
  double follow_sum_ = 0.0;
  std::uint64_t follow_samples_ = 0;
  std::size_t follow_steps_ = 0;
  double last_step_error_ = std::numeric_limits<double>::quiet_NaN();  // its mean
  bool within_ = false;           // the offset has come within the tolerance
  std::size_t steps_within_ = 0;  // follow steps since
  // The offset within the tolerance (once: following the error may move it out again), and a
  // follow step's mean error within `settled` since (or the steps the settling waits played).
  bool settled(double tare) noexcept;
  double checkpoint_gap_ = std::numeric_limits<double>::quiet_NaN();
  bool stalled_ = false;
  // Deciding with the other axes: the end this axis would take at pending_tick_.
  LeadInTogether* together_ = nullptr;
  bool pending_ = false;
  std::uint64_t pending_tick_ = 0;  // its lead-in period's first tick
  LeadInEnd pending_end_ = LeadInEnd::kLongest;
  double pending_error_ = 0.0;
  void end_lead_in(std::uint64_t k, std::uint64_t begun, LeadInEnd end) noexcept;
};

}  // namespace hystbench::daemon
