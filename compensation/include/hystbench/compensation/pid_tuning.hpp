#pragma once
// Default feedback gains for `inverse+pid` and `pid`, derived from the model and the loop rate so
// that the feedback never makes tracking worse than the feedforward alone:
//   - integral action only (kp = kd = 0): u_fb changes smoothly, sensor noise is not amplified;
//   - crossover f_c = bandwidth_hz, by default min(loop rate / 500, 20 Hz), at most a twentieth
//     of the model's natural frequency when it has dynamics: ki = 2 pi f_c / g, g the model's
//     mean slope [µm/V], so |S| <= ~1 at every frequency. The margin is for what a model may not
//     hold: a lightly damped resonance and a gain that grows with |du/dt| together turn per-tick
//     feedback changes into a limit cycle at the resonance (seen at 50 Hz on the loopback with
//     rate dependence on: 5 % rms at 1 Hz instead of 0.7 %);
//   - the output low-passed at 4 f_c;
//   - for a rate-dependent model, whose output reacts to |du/dt| with a gain up to
//     K_r = sum_i |c_i - c_{i-1}| * max|u| [µm per V/s], f_c is lowered until the high-frequency
//     loop gain ki * 2 pi f_lp * K_r stays at a quarter of 1 / (1.5 loop periods) (phase margin).
// Not real-time (runs when a run is built).
#include <string>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/pid_controller.hpp"

namespace hystbench::compensation {

struct PidTuning {
  double kp = 0.0;                ///< [V/µm]
  double ki = 0.0;                ///< [V/(µm s)]
  double kd = 0.0;                ///< [V s/µm]
  double output_filter_hz = 0.0;  ///< [Hz]
  double bandwidth_hz = 0.0;      ///< the crossover used [Hz]
  std::string basis;              ///< how the numbers were reached, for the run's result
};

/// gain_um_per_v > 0 is the actuator's mean slope; loop_rate_hz > 0; bandwidth_hz <= 0 = the
/// default; model may be null (then only the gain and the loop rate count).
/// Throws std::invalid_argument for a non-positive gain or loop rate.
PidTuning tune_pid(double gain_um_per_v, double loop_rate_hz, double bandwidth_hz,
                   const ActuatorModel* model);

}  // namespace hystbench::compensation
