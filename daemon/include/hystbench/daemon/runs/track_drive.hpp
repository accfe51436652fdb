#pragma once
// The track kind's drive (RunDrive): a reference through a compensator after the program's
// precondition sweep, with what only tracking needs: the tare of the model's offset, the
// dynamics preview, the targets ahead and the learned drive's trials. A const program
// (TrackProgram, filled by the builders runs/details/track_program.cpp, stage_track.cpp,
// inverse_track_program.cpp) and the run's state apart (TrackState): configure() makes the state
// from the program and sizes its buffers; the loop calls the rest within the tick (real-time
// safe: noexcept, no allocation).
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>

#include "hystbench/compensation/compensator.hpp"
#include "hystbench/compensation/dynamics_inversion.hpp"
#include "hystbench/daemon/loop/run_drive.hpp"
#include "hystbench/daemon/loop/run_program.hpp"
#include "hystbench/daemon/loop/target_window.hpp"
#include "hystbench/daemon/runs/learning_exchange.hpp"
#include "hystbench/sim/signal_generator.hpp"

namespace hystbench::daemon {

/// The output offset the model does not predict (slow creep, a sensor offset): the mean of
/// y - y_model over the precondition sweep's ticks [from, first tick of the reference) is
/// subtracted from the feedforward's target (not from the reference the error and the PID see).
/// The windows the builders set; the loop measures them into a TareMeasure.
struct TareWindow {
  /// The window's first tick; >= the sweep's length = no tare.
  std::uint64_t from = std::numeric_limits<std::uint64_t>::max();
  /// The driver exchange latency that the model's delay already holds [ticks]: an identified
  /// model's exchange_ticks, 0 for a model made elsewhere. A reading that answers the output of
  /// response_ticks ago is compared with y_model of (response_ticks - this) ago.
  std::uint64_t model_exchange_ticks = 0;
  /// A periodic reference: the mean of y - y_ref over its second unscored period,
  /// [startup_from, startup_to), is added to the tare from startup_to on: the offset of the
  /// periodic motion that the prefix's slow sweep does not show (a fast drive moves a loop's
  /// mean differently from the model's). startup_from >= startup_to: none.
  std::uint64_t startup_from = std::numeric_limits<std::uint64_t>::max();
  std::uint64_t startup_to = 0;
};

/// What the loop measured over a run's tare windows (TareWindow). Real-time safe.
struct TareMeasure {
  static constexpr std::size_t kHistory = 64;      ///< y_model ticks kept
  std::array<double, kHistory> y_model_history{};  ///< y_model of tick k at k % kHistory
  bool predicted = false;                          ///< a y_model has been recorded
  double sum = 0.0;                                ///< of y - y_model over the window [µm]
  std::uint64_t samples = 0;
  double startup_sum = 0.0;  ///< of y - y_ref over the start-up window [µm]
  std::uint64_t startup_samples = 0;

  /// The sweep's tare [µm] (0 until the window has a sample).
  double um() const noexcept { return samples > 0 ? sum / static_cast<double>(samples) : 0.0; }
  /// The start-up's offset [µm] (0 without a sample).
  double startup_um() const noexcept {
    return startup_samples > 0 ? startup_sum / static_cast<double>(startup_samples) : 0.0;
  }
  /// The tare the feedforward applies at tick k [µm].
  double um_at(std::uint64_t k, const TareWindow& w) const noexcept {
    return um() + (k >= w.startup_to ? startup_um() : 0.0);
  }
};

/// A track run's program: what its builders and its preparation decide on the control thread
/// before the run. The loop only reads it; a run's changing state is its TrackState, made from
/// the program by TrackDrive::configure(), so the program is the same after the run as before.
struct TrackProgram {
  /// The reference [µm] as a function of time since its first tick [s].
  std::unique_ptr<sim::SignalGenerator> reference;
  /// A stage: the feedforward's reference in place of `reference`, the target with the coupling
  /// taken out (static decoupling); the error and the feedback keep `reference`. Null: it.
  std::unique_ptr<sim::SignalGenerator> feedforward_reference;
  /// The compensator as the run starts (its operators relaxed); the run steps a copy.
  std::optional<compensation::Compensator> compensator;
  /// The model's delay and dynamics inverted from the previewed reference (the feedforward then
  /// inverts its target, not y_ref); absent for a static model or `none`/`pid`.
  std::optional<compensation::DynamicsInversion> preview;
  /// References outside [y_ref_min, y_ref_max] are clipped and flagged [µm].
  double y_ref_min = -std::numeric_limits<double>::infinity();
  double y_ref_max = std::numeric_limits<double>::infinity();
  TareWindow tare;
  /// The tick at which the feedback's resonators restart from rest (the end of a periodic
  /// reference's start from rest, which they would otherwise take for its repeated error); 0: none.
  std::uint64_t harmonics_from = 0;
  /// --learned: the compensator again, fed the targets at the offset the drive was learned at
  /// (learned_twin_offset_um) with its feedback held; the drive moves by how far the
  /// compensator's feedforward is from its twin's at the same tick: the target offset's effect
  /// alone, where the compensator's slow states (a model's creep, relaxed at the run's start)
  /// move both alike (LearningExchange::learned()). Absent otherwise; the run steps a copy.
  std::optional<compensation::Compensator> learned_twin;
  double learned_twin_offset_um = 0.0;

  /// The feedforward's target at time t_s since the reference's first tick [s]: the reference
  /// clipped to [y_ref_min, y_ref_max], or with a preview the static target that inverts the
  /// model's delay and dynamics (the reference ahead); less `tare_um`. Real-time safe.
  double feedforward_target(double t_s, double tare_um) const noexcept;
  /// The reference at t_s [µm], clipped to [y_ref_min, y_ref_max]. Real-time safe.
  double clipped_reference(double t_s) const noexcept;
};

/// A track run's state: made from its program by TrackDrive::configure() (control thread), then
/// written by the loop thread alone; read for the result after the run.
struct TrackState {
  std::optional<compensation::Compensator> compensator;   ///< the program's, stepped
  std::optional<compensation::Compensator> learned_twin;  ///< the program's, stepped
  TareMeasure tare;
  double dt = 0.0;               ///< the loop's period [s]
  std::uint64_t first_tick = 0;  ///< the reference's first tick (after the sweep)
  TargetWindow targets;          ///< the feedforward's targets ahead (configure() sizes it)
  TargetWindow twin_targets;     ///< the twin's, sized as targets
  // ---- this tick's, from update() to scored() ----
  double u_compensator = 0.0;  ///< the compensator's feedforward, for a learning trial
  std::size_t phase = 0;       ///< the learning trial's phase
  bool trial_tick = false;     ///< the tick belongs to a learning trial, at phase
  bool lead_in = false;        ///< a drive learned before plays the period before trial 0
};

class TrackDrive final : public RunDrive {
 public:
  /// Set by the builders and the run's preparation before the run; read only from configure()
  /// on.
  TrackProgram program;
  /// --learn: the trials' hand-over with the learner on the control thread (null for a run that
  /// does not learn). From its first_tick on, a period that plays a learned drive plays it in
  /// place of the compensator's feedforward (its feedback stays on).
  std::unique_ptr<LearningExchange> learning;
  /// A stage's replay (axis 0's drive holds it): its axes' lead-ins end together.
  std::unique_ptr<LearningExchange::LeadInTogether> lead_in_together;

  /// The run's state (for the result after the run; the loop thread's during it).
  const TrackState& state() const noexcept { return state_; }

  // ---- RunDrive ----
  /// Makes the run's state from the program: a second configure() starts the run again.
  void configure(const DriveSetup& setup) override;
  bool awaits(std::uint64_t k) const noexcept override;
  DriveCommand update(const DriveInput& in) noexcept override;
  void limited(int direction) noexcept override;
  void predicted(std::uint64_t k, double y_model) noexcept override;
  void measured(std::uint64_t k, const drivers::Measurement& m) noexcept override;
  DriveScore scored(std::uint64_t k, double y_ref, double y_measured,
                    double u_ff) noexcept override;

 private:
  double twin_feedforward(double t) noexcept;

  TrackState state_;
};

/// The track drive of `p` (null for a program of another kind). Any thread that owns `p`.
TrackDrive* track_drive(RunProgram& p) noexcept;
const TrackDrive* track_drive(const RunProgram& p) noexcept;
/// Gives `p` a new track drive and returns it (for the builders).
TrackDrive& make_track_drive(RunProgram& p);

}  // namespace hystbench::daemon
