#pragma once
// The contract between the loop and a run kind: what the loop asks of a kind at every tick. A run
// plays its program's open-loop excitation first (identify, excite and frf are nothing else;
// track's precondition sweep is its prefix); from the tick after it on, its drive's update()
// gives the output. The loop limits the output, exchanges with the driver, watches the feedback
// and scores the errors; everything a kind keeps for itself (track's compensator, tare, preview
// and learning) lives in its drive. Adding a run kind is a drive and the builder that makes its
// program (docs/architecture.md, "Adding a run kind").
//
// configure() runs on the control thread before the run and may allocate. Every other call is
// made by the loop thread within the tick: noexcept, no allocation, no lock, no system call.
#include <cstdint>
#include <limits>

#include "hystbench/drivers/driver.hpp"

namespace hystbench::daemon {

/// What the loop tells a drive before the run.
struct DriveSetup {
  double dt_s = 0.0;                ///< the loop's period [s]
  double u_min = 0.0, u_max = 0.0;  ///< the output range the limiter holds [V]
  std::uint64_t first_tick = 0;     ///< the first tick update() gives: the excitation's length
};

/// What the loop hands a drive at tick k.
struct DriveInput {
  std::uint64_t k = 0;  ///< the run's tick (0 = its first)
  /// The last fresh reading [µm]; NaN when the last reading was stale or followed a stall of the
  /// exchange (ReadingLateness): the feedback holds.
  double y = std::numeric_limits<double>::quiet_NaN();
  bool feedback_on = false;  ///< k >= the program's feedback_from: the feedback may act
  /// How much later y answered than the run's usual readings [ticks] (ReadingLateness): the
  /// feedback compares it with the reference of that many ticks before.
  std::uint64_t y_late_ticks = 0;
};

/// What a drive asks of tick k.
struct DriveCommand {
  double y_ref = std::numeric_limits<double>::quiet_NaN();  ///< reference [µm]; NaN: none
  double u = 0.0;     ///< the output asked for, before the limiter [V]
  double u_ff = 0.0;  ///< its feedforward [V] (logged)
  double u_fb = 0.0;  ///< its feedback [V] (logged)
  std::uint32_t flags =
      0;  ///< SampleFlags the drive raised (reference clipped, feedback saturated)
  bool trial_ends = false;  ///< the tick ends a trial the control thread waits for (learning)
};

/// What scoring tick k tells the loop.
struct DriveScore {
  bool last_trial = false;  ///< the run's last trial has played: the run completes
  /// The first scored tick moved up to here (a learned drive's lead-in that ended early): the
  /// loop moves metrics_from, and feedback_from where it began with it. Max: unchanged.
  std::uint64_t scored_from = std::numeric_limits<std::uint64_t>::max();
};

class RunDrive {
 public:
  virtual ~RunDrive() = default;

  /// Before the run, on the control thread (may allocate).
  virtual void configure(const DriveSetup& setup) { (void)setup; }
  /// Simulated clock only: true while tick k must wait for the control thread (a learner's next
  /// drive); the loop waits, unless a stop, an abort or a shutdown comes.
  virtual bool awaits(std::uint64_t k) const noexcept {
    (void)k;
    return false;
  }
  /// Tick k's output, for every tick after the program's excitation.
  virtual DriveCommand update(const DriveInput& in) noexcept = 0;
  /// Every tick: which bound the limiter held the output at (+1 above, -1 below, 0 none).
  virtual void limited(int direction) noexcept { (void)direction; }
  /// Every tick of a run with a model: its prediction for the output applied at tick k [µm] (on a
  /// stage, the coupled one replaces the axis's own in the same tick).
  virtual void predicted(std::uint64_t k, double y_model) noexcept { (void)k, (void)y_model; }
  /// Every fresh reading at tick k (it answers the output of m.response_ticks ago).
  virtual void measured(std::uint64_t k, const drivers::Measurement& m) noexcept {
    (void)k, (void)m;
  }
  /// Every tick without a fault, after the exchange: the reference and the reading [µm] and the
  /// feedforward the loop logged [V].
  virtual DriveScore scored(std::uint64_t k, double y_ref, double y_measured,
                            double u_ff) noexcept {
    (void)k, (void)y_ref, (void)y_measured, (void)u_ff;
    return {};
  }
};

}  // namespace hystbench::daemon
