#pragma once
// A frequency response measured in place with a periodic excitation (a multisine around an
// operating point) and its estimate from whole periods of the record: per excited line, the
// ratio of the output's and the input's DFT averaged over the periods, the noise of that mean
// (the spread from period to period over sqrt(periods)) and the coherence. Before the DFT a
// straight line through each signal over the averaged periods is taken off (the creep and drift
// of a hold, which would leak into every line). What does not repeat from period to period is
// the output's noise: its rms is kept too. The lines are DFT bins of one period: line m is
// m / (period dt) Hz. Pure maths (Eigen's FFT); allocates: not real-time.
#include <complex>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

namespace hystbench::compensation {

struct MeasuredResponse {
  std::vector<double> frequency_hz;            ///< strictly increasing, > 0 [Hz]
  std::vector<std::complex<double>> response;  ///< output / input at each frequency
  std::vector<double> noise;                   ///< standard deviation of `response`, >= 0
  std::vector<double> coherence;               ///< in [0, 1]
  double operating_point = 0.0;                ///< the input the excitation sat on [input unit]
  double amplitude = 0.0;                      ///< the excitation's peak [input unit]
  double output_noise_rms = 0.0;  ///< the output's part that does not repeat [output unit]
  std::string label;              ///< where and how it was measured, for reports

  std::size_t size() const noexcept { return frequency_hz.size(); }
};

/// Where a response was measured in its drive: `periods` periods of `period` samples from
/// `first` on.
struct ResponseSegment {
  std::size_t first = 0, period = 0, periods = 0;
};

/// The response from `periods` whole periods of u and y (u.size() == y.size() == periods x
/// period, periods >= 2; y[k] the reading of the tick that applied u[k]) at the excited DFT
/// lines (each in [1, period / 2)), sampled at rate_hz. Throws std::invalid_argument for
/// mismatched lengths, fewer than two periods, a line out of range or one the input does not
/// excite.
MeasuredResponse estimate_response(std::span<const double> u, std::span<const double> y,
                                   std::size_t period, std::span<const std::size_t> lines,
                                   double rate_hz);

/// Throws std::invalid_argument naming the field (`what`.frequency_hz[i], ...) when r's vectors
/// differ in length, a frequency is not finite, positive and increasing, a response not finite,
/// a noise negative or a coherence outside [0, 1].
void validate(const MeasuredResponse& r, const std::string& what);

}  // namespace hystbench::compensation
