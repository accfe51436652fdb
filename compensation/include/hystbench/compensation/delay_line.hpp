#pragma once
// Pure transport delay of a whole number of samples plus a fraction of one more, the fraction
// interpolated linearly between the two samples around it (a delay of 0.5 samples returns the
// mean of the last two inputs). Storage is allocated at construction; push() is real-time safe.
#include <cmath>
#include <cstddef>
#include <vector>

namespace hystbench::compensation {

class DelayLine {
 public:
  /// `samples` whole samples, plus `fraction` in [0, 1) of one more.
  explicit DelayLine(std::size_t samples = 0, double fraction = 0.0)
      : buf_(samples + (fraction > 0.0 ? 2 : 1), 0.0), fraction_(fraction > 0.0 ? fraction : 0.0) {}
  /// A delay of `samples` >= 0 (not necessarily whole); within 1e-9 of a whole number it is
  /// that whole number.
  static DelayLine of(double samples) {
    const double whole = std::floor(samples + 1e-9);
    const double fraction = samples - whole;
    return DelayLine(static_cast<std::size_t>(whole > 0.0 ? whole : 0.0),
                     fraction > 1e-9 ? fraction : 0.0);
  }
  /// Pushes x and returns the value pushed `samples` calls ago (interpolated toward the one
  /// before it by the fraction).
  double push(double x) noexcept {
    buf_[head_] = x;
    if (++head_ == buf_.size()) head_ = 0;  // no division in the per-sample path
    if (fraction_ == 0.0) return buf_[head_];
    // buf_[head_] is now the oldest value (samples + 1 ago), the next one `samples` ago.
    const std::size_t newer = head_ + 1 == buf_.size() ? 0 : head_ + 1;
    return fraction_ * buf_[head_] + (1.0 - fraction_) * buf_[newer];
  }
  void reset(double x0) noexcept {
    for (auto& v : buf_) v = x0;
  }
  /// The whole samples of the delay (without the fraction).
  std::size_t samples() const noexcept { return buf_.size() - (fraction_ > 0.0 ? 2 : 1); }
  double fraction() const noexcept { return fraction_; }

 private:
  std::vector<double> buf_;
  double fraction_ = 0.0;
  std::size_t head_ = 0;
};

}  // namespace hystbench::compensation
