#pragma once
// Moving average over one period of a periodic signal, a fractional number of samples long:
//   a(k) = (x(k) + ... + x(k-n+1) + f x(k-n)) / N,   N = n + f samples, 0 <= f < 1.
// Its gain is zero at 1/(N T) and at every harmonic, one at DC, and its delay is (N - 1) T / 2:
// it keeps a signal's slow part and removes whatever repeats with the period. The history
// starts at zero. Storage is allocated at construction; step() is real-time safe.
#include <cstddef>
#include <vector>

namespace hystbench::compensation {

class PeriodAverage {
 public:
  /// period_samples >= 1 (the period over the sample time); below 1 the average is the input.
  /// Throws std::invalid_argument for NaN or a negative length.
  explicit PeriodAverage(double period_samples = 0.0);

  /// Pushes x and returns the average of the last period, the sample it leaves included.
  double step(double x) noexcept;
  /// Clears the history to zero.
  void reset() noexcept;
  /// The window's length N [samples]; 0 when it passes the input through.
  double period_samples() const noexcept { return length_; }

 private:
  std::vector<double> buf_;  // the newest n + 1 samples; buf_[head_] the oldest
  std::size_t head_ = 0;
  double sum_ = 0.0;  // of the newest n
  double fraction_ = 0.0;
  double length_ = 0.0;
};

}  // namespace hystbench::compensation
