#pragma once
// Default feedback gains for `inverse+pid` and `pid`, derived from the model and the loop rate so
// that the feedback never makes tracking worse than the feedforward alone:
//   - integral action only (kp = kd = 0): u_fb changes smoothly, sensor noise is not amplified;
//   - crossover f_c = bandwidth_hz, by default min(loop rate / 500, 2 Hz), at most a twentieth
//     of the model's natural frequency when it has dynamics: ki = 2 pi f_c / g, g the model's
//     mean slope [µm/V]. Low, because above f_c an integral loop with any extra lag (delay,
//     output filter, a hysteretic or rate-dependent gain) has |S| > 1 (a crossover of tens of
//     Hz makes a rate-free actuator worse above it, and leaves a limit cycle on a
//     rate-dependent one);
//   - the output low-passed at 100 f_c for a rate-free model (a filter near f_c is itself the lag
//     that makes |S| > 1 a little above it), at 4 f_c for a rate-dependent one;
//   - for a rate-dependent model, whose output reacts to |du/dt| with a gain up to
//     K_r = sum_i |c_i - c_{i-1}| * max|u| [µm per V/s]: on a falling branch a faster fall raises
//     the output, so to a small change of the drive the actuator is g - K_r s, a right-half-plane
//     zero at g / K_r. f_c is lowered to (g / K_r) / (2 pi 14) (closer to the zero, the
//     integrator answers the transients at the reversal tops and leaves a tail that makes the
//     tracking worse than the inverse alone), and further until the
//     high-frequency loop gain ki * 2 pi f_lp * K_r stays at a quarter of 1 / (1.5 loop periods).
//   - behind a model's inverse whose reference is periodic with f_0 > f_c / 2 (f_0 > f_c behind
//     the linear map, whose error is the hysteresis loop itself, carried by its fundamental,
//     which the loop lowers below its crossover), the error is averaged
//     over one period first (PeriodAverage) and f_c is at most f_0 / 10 (the average delays by
//     half a period; at f_0 / 4 the mean error alternated in sign from period to period). What
//     repeats with such a reference is the feedforward's model error at f_0 and its harmonics,
//     at or above the crossover: an integral loop cannot lower it there, only raise it by
//     |S| - 1 > 0 (any lag, the rate law's zero above all; near the crossover the loop lowers
//     the fundamental but raises the harmonics). The loop keeps the slow errors (offset, drift,
//     creep), which the average passes. docs/measurements.md has the figures behind these
//     rules (inverse against inverse+pid on each truth).
// Not real-time (runs when a run is built).
#include <string>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/pid_controller.hpp"

namespace hystbench::compensation {

/// What the feedback is added to: a model's inverse (`inverse+pid`) or the linear map (`pid`).
enum class FeedforwardKind { kModelInverse, kLinearMap };

struct PidTuning {
  double kp = 0.0;                ///< [V/µm]
  double ki = 0.0;                ///< [V/(µm s)]
  double kd = 0.0;                ///< [V s/µm]
  double output_filter_hz = 0.0;  ///< [Hz]
  double bandwidth_hz = 0.0;      ///< the crossover used [Hz]
  double error_period_s = 0.0;    ///< average the error over this period first [s]; 0 = none
  std::string basis;              ///< how the numbers were reached, for the run's result
};

/// gain_um_per_v > 0 is the actuator's mean slope; loop_rate_hz > 0; bandwidth_hz <= 0 = the
/// default; model may be null (then only the gain and the loop rate count); reference_hz > 0 is
/// the fundamental of a periodic reference the feedforward follows (0: none, or not periodic),
/// behind the model's inverse or the linear map (`pid`).
/// Throws std::invalid_argument for a non-positive gain or loop rate.
PidTuning tune_pid(double gain_um_per_v, double loop_rate_hz, double bandwidth_hz,
                   const ActuatorModel* model, double reference_hz = 0.0,
                   FeedforwardKind feedforward = FeedforwardKind::kModelInverse);

}  // namespace hystbench::compensation
