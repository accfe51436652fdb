#pragma once
// The stage's response while it moves: a small sine carried on ramps up and down (sim's
// frequency_response_excitation.hpp, its moving part), its phasor in the output over the one in
// the input on each ramp, by least squares against a cubic (the hysteresis branch the ramp
// climbs, and the creep) and the sine's cosine and sine. A rate law acts only while the stage
// moves; one whose rate lowers the output puts a right-half-plane zero on one direction's
// branches and a left-half-plane one on the other's, so that direction's ramps lag the other's:
//   falling / rising = (1 - j f / z) / (1 + j f / z),   lag = 2 atan(f / z).
// A rate-independent stage (its modes and creep act alike both ways) lags neither. The zero the
// lag implies, z = f / tan(lag / 2), is what a loop around the moving stage must hold; a lag
// within its noise implies none. Pure maths (Eigen); allocates: not real-time.
#include <complex>
#include <cstddef>
#include <span>
#include <string>

namespace hystbench::compensation {

/// One ramp of the record: `length` samples from `first` on.
struct MovingRamp {
  std::size_t first = 0, length = 0;
  bool rising = true;
};

struct MovingResponse {
  double frequency_hz = 0.0;     ///< the sine's [Hz]
  std::complex<double> rising;   ///< output / input at the sine on the rising ramps (mean)
  std::complex<double> falling;  ///< the same on the falling ramps
  std::size_t ramps = 0;         ///< averaged, both directions
  double lag_deg = 0.0;          ///< how far the lagging direction trails the other, >= 0
  double lag_noise_deg = 0.0;    ///< the standard deviation of that difference
  std::string lagging;           ///< "rising" or "falling"
  double zero_hz = 0.0;          ///< f / tan(lag / 2); 0 when the lag is within its noise
};

/// The response from the ramps of u and y (y[k] the reading of the tick that applied u[k]) at
/// frequency_hz, sampled at rate_hz. A lag counts when it exceeds three times its noise (the
/// spread of each direction's ramps) and min_lag_deg. Throws std::invalid_argument for
/// mismatched lengths, a ramp out of the record or shorter than two cycles of the sine, no ramp
/// of one direction, or a sine the input does not carry.
MovingResponse estimate_moving_response(std::span<const double> u, std::span<const double> y,
                                        std::span<const MovingRamp> ramps, double frequency_hz,
                                        double rate_hz, double min_lag_deg = 0.5);

}  // namespace hystbench::compensation
