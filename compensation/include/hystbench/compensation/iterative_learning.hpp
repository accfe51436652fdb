#pragma once
// Iterative learning control over a periodic trial: the next trial's drive from this trial's drive
// and its measured error,
//   u_{k+1}(j) = u_k(j) + Q[ (gamma Q[e_k](j + d) + r_k) / s_k(j) ]   (u_0 through Q first),
// circular over the trial's P samples, u_k the drive as learned before the drive limits cut it
// (at most a fifth of their span beyond them; the trial plays it within the limits, and what they
// cut, which holds harmonics above Q, stays out of what is learned), r_k the offset's drift over a
// trial (creep settling, a thermal drift), which a correction of the last error alone would trail
// by r / gamma: what the trial's mean error moved beyond what the last mean correction should have
// moved it, each pair moving the estimate half-way; only over trials of 0.5 s or more (over a
// shorter one the drift is below what its mean shows beside the loop's nonlinearity and a wrong
// model's gain on the correction). L comes from the active model: d its input delay (the error is
// read d ahead of the drive that caused it; from the second update on, the delay the bench shows:
// where the output's change between two trials best follows the drive's, the median over the pairs
// where that is clear), s_k(j) the local slope of its static map along the trial's drive (the
// inverse's slope there), kept within [1/4, 4] x its mean along the trial. Where j + d wraps past
// the trial's end, e_k there answered the drive u_{k-1} ended with, and the next trial's start
// answers u_k's: half of s_k(j) (u_k(j) - u_{k-1}(j)) is taken off it first (the change made
// there a trial before, else learned twice and the start swings from trial to trial; half, as the
// bench may answer with less than the slope there). The model's
// second-order dynamics are not inverted on the error: they bound Q below 0.9 of their natural
// frequency, and within that band the bench's gain, which a fitted mode's damping and a
// rate-dependent loop move, is what a learning of gain 1/2 meets either way (inverted by the
// error's differences, a fast trial's few samples a period approximate the mode poorly near it;
// docs/measurements.md compares the two). Q is a zero-phase low-pass (a fourth-order Butterworth
// run forward and backward around the trial), cut off at the lowest of a fifth of the sample rate
// and the 300th harmonic of the trial's fundamental (above it a slow trial's error is mostly sensor
// noise), but past its fifth harmonic within 0.3 of the sample rate (a fast trial's error is mostly
// its odd harmonics), and below 0.9 of the model's natural frequency (a mode it misses would grow
// from trial to trial). A fast trial (that floor sets Q) also learns its harmonics above Q, to
// 0.45 of the sample rate, where a mode is known (the model's, else the one the bench's step
// responses timed, LearningOptions::bench_mode), the bench's delay measured (three trial pairs),
// and the error Q leaves out at least half of what it passes: each harmonic of that error,
// divided by the mode's exact response there and the delay, through s_k (the error of a 500 Hz
// trial beside a 3 kHz mode is mostly its sixth harmonic, which the mode lifts and Q cuts).
// Pure maths, no I/O; allocates: off the real-time path.
#include <array>
#include <complex>
#include <cstddef>
#include <optional>
#include <span>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/second_order_dynamics.hpp"

namespace hystbench::compensation {

/// The response a learned drive's change meets at each frequency, over the model's local slope:
/// the stage as measured in place (its frequency responses through the model or the linear map,
/// compensation/feedback_plant.hpp), and where a feedback runs beside the learning, times the
/// loop's sensitivity S (the loop takes out part of each change). Lines increasing in frequency.
struct MeasuredLearningPlant {
  std::vector<double> frequency_hz;
  std::vector<std::complex<double>> response;
  std::vector<double> stage_gain;  ///< |the stage's part| alone (without S), for each line
};

struct LearningOptions {
  double dt = 1e-4;        ///< sample period [s], > 0
  double cutoff_hz = 0.0;  ///< Q's cut-off [Hz]; 0 = the default above (set: nothing above it)
  /// The trial's fundamental for the harmonic bound [Hz]; 0 = its repetition rate (a trial
  /// that holds several cycles, a raster's lines in one pass, gives theirs).
  double fundamental_hz = 0.0;
  double u_min = -1e300;    ///< the learned drive stays within [u_min, u_max] [input unit]
  double u_max = 1e300;     ///<
  double max_step = 1e300;  ///< largest change between samples [input unit] (slew x dt)
  double min_slope = 0.25;  ///< local slope floor, a fraction of its mean along the trial
  double max_slope = 4.0;   ///< local slope cap, a multiple of that mean
  /// The bench's mode where the model has none (its identify's step timing): a fast trial
  /// learns its harmonics above Q through it. Unused where the model has dynamics.
  std::optional<DynamicsParameters> bench_mode;
  /// The response measured in place. When given it replaces the model's delay and mode: each
  /// harmonic of the correction is divided by it at its frequency (it holds the delay, the modes
  /// and what the model lacks, as measured), Q is not held below a mode, and only harmonics
  /// where the stage's gain is 1/4 or more (an inverse would amplify the noise elsewhere) and
  /// within its lines are learned. The trial's start, which answered the drive the trial before
  /// ended with, has the change made there taken off first, as where the error is advanced.
  std::optional<MeasuredLearningPlant> measured_plant;
};

class IterativeLearning {
 public:
  /// `model`: the active model (copied). period_samples >= 4. Throws std::invalid_argument for
  /// an empty model or bad options.
  IterativeLearning(const ActuatorModel& model, std::size_t period_samples,
                    LearningOptions options);

  /// The next trial's drive into `next` (P samples): drive (this trial's feedforward, P samples)
  /// corrected by gain (gamma, 0 < gain <= 1) times the learned step from error (y_ref - y,
  /// P samples; error[j] is the reading of the tick that played drive[j]). Drive limits hold.
  /// The first call's drive (the compensator's) is itself passed through Q.
  void update(std::span<const double> drive, std::span<const double> error, double gain,
              std::span<double> next);

  /// The model's local slope along the last drive given to update() [output / input unit].
  const std::vector<double>& slope() const noexcept { return slope_; }
  double cutoff_hz() const noexcept { return cutoff_hz_; }
  /// The delay the error is read ahead by [samples]: the model's, or the bench's once measured.
  double delay_samples() const noexcept { return advance_samples_; }
  double model_delay_samples() const noexcept { return model_delay_samples_; }
  /// The bench's delay [samples] from each trial pair that showed it clearly, in order.
  const std::vector<double>& delay_measurements() const noexcept { return delays_; }
  std::size_t period_samples() const noexcept { return period_; }
  /// A fast trial's: the harmonics above Q are learned through this mode (none otherwise).
  std::optional<DynamicsParameters> high_band_mode() const {
    return mode_ ? std::optional(mode_->parameters()) : std::nullopt;
  }
  bool fast_trial() const noexcept { return fast_trial_; }
  /// The updates that learned the harmonics above Q.
  std::size_t high_band_updates() const noexcept { return high_band_updates_; }
  /// The learning divides each harmonic by the response measured in place (options).
  bool uses_measured_plant() const noexcept { return o_.measured_plant.has_value(); }
  /// Harmonics the last update learned through it, and those it left out (the stage's gain
  /// below 1/4).
  std::size_t measured_harmonics() const noexcept { return measured_harmonics_; }
  /// The delay the bench shows beyond what the measured response holds [samples]: found in
  /// place from the trial pairs (the output's change against the drive's through the
  /// response), 0 until a median of three is half a sample or more; the response is moved by it.
  double residual_delay_samples() const noexcept { return residual_delay_samples_; }
  std::size_t measured_harmonics_left_out() const noexcept { return measured_left_out_; }

 private:
  void local_slope(std::span<const double> drive);
  // The drive's change from the trial before (last_drive_) through the slope along it, and the
  // output's change (from last_error_), both through Q, into cu and cy.
  void pair_changes(std::span<const double> drive, std::span<const double> error,
                    std::vector<double>& cu, std::vector<double>& cy);
  // The bench's delay from this trial and the one before (last_drive_, last_error_).
  void measure_delay(std::span<const double> drive, std::span<const double> error);
  // The same through the measured response: the delay it lacks.
  void measure_residual_delay(std::span<const double> drive, std::span<const double> error);
  // Q: zero-phase low-pass in place, circular over the trial.
  void low_pass(std::vector<double>& x);
  // The error filtered by Q, read advance_samples_ ahead of the drive that caused it, less
  // (where that wraps to the trial's start) a share of what the trial changed since `before`.
  std::vector<double> advanced_error(std::span<const double> error, std::span<const double> drive,
                                     const std::vector<double>& before);
  // What the trial changed at drive sample j (from `before`, the trial before's drive) does to
  // the next trial's start where the error read advance_samples_ ahead wraps there: kWrapShare of
  // the model's slope times the change, else 0 [output unit].
  double wrapped_change(std::span<const double> drive, const std::vector<double>& before,
                        std::size_t j) const;
  // The same taken off the error where it lands (advance_samples_ on, around the trial).
  void take_off_wrapped_change(std::span<const double> drive, const std::vector<double>& before,
                               std::vector<double>& error) const;
  // A fast trial's harmonics above Q: each through the mode and the bench's delay.
  void add_high_band(std::span<const double> error, double gain, std::vector<double>& correction);
  bool in_high_band(std::size_t h) const;
  // x's h-th harmonic over the trial (unscaled DFT).
  std::complex<double> harmonic(std::span<const double> x, std::size_t h) const;
  // The measured plant at f_hz and the stage's gain there: its lines (measured_lines), moved by
  // the delay found in place that they lack (residual_delay_samples_).
  std::complex<double> measured_response(double f_hz, double& stage_gain) const;
  // The measured plant's lines at f_hz, interpolated between them (0 beyond the top one).
  std::complex<double> measured_lines(double f_hz, double& stage_gain) const;
  // x through the measured plant's inverse, harmonic by harmonic, in place.
  void through_measured_inverse(std::vector<double>& x);
  // The model's mode at w [rad / sample]: its discrete response, output over input.
  std::complex<double> mode_response(double w) const;

  ActuatorModel model_;                      // static: its slope along the trial
  std::optional<SecondOrderDynamics> mode_;  // a fast trial's high band's mode
  bool fast_trial_ = false;
  std::size_t high_band_updates_ = 0;
  std::size_t measured_harmonics_ = 0, measured_left_out_ = 0;
  std::size_t period_;
  LearningOptions o_;
  double cutoff_hz_ = 0.0;
  double advance_samples_ = 0.0;                 // the delay the error is read ahead by [samples]
  double model_delay_samples_ = 0.0;             // the model's
  std::vector<double> delays_;                   // the bench's, measured
  std::vector<double> residual_delays_;          // beyond the measured response's, measured
  double residual_delay_samples_ = 0.0;          // the response moved by it
  std::vector<double> last_drive_, last_error_;  // the trial the last update was given
  // Butterworth sections (b0, b1, b2, a1, a2) of Q, and the warm-up periods its circular run needs.
  std::vector<std::array<double, 5>> sections_;
  std::size_t warmup_periods_ = 1;
  std::vector<double> slope_, work_, shifted_;
  // The last drive offered (limits held), and the same before the drive limits cut it: the next
  // correction adds to it when the trial played the one offered.
  std::vector<double> offered_, unlimited_;
  std::size_t updates_ = 0;
  // The offset's drift over a trial [output unit], estimated from the trials' mean errors and the
  // mean corrections that followed them, and added to each correction.
  double drift_ = 0.0, last_mean_error_ = 0.0, last_mean_step_ = 0.0;
};

}  // namespace hystbench::compensation
