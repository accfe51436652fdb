#pragma once
// Pure transport delay of a whole number of samples. Storage is allocated at construction;
// push() is real-time safe.
#include <cstddef>
#include <vector>

namespace hystbench::compensation {

class DelayLine {
 public:
  explicit DelayLine(std::size_t samples = 0) : buf_(samples + 1, 0.0) {}
  /// Pushes x and returns the value pushed `samples` calls ago.
  double push(double x) noexcept {
    buf_[head_] = x;
    if (++head_ == buf_.size()) head_ = 0;  // no division in the per-sample path
    return buf_[head_];
  }
  void reset(double x0) noexcept {
    for (auto& v : buf_) v = x0;
  }
  std::size_t samples() const noexcept { return buf_.size() - 1; }

 private:
  std::vector<double> buf_;
  std::size_t head_ = 0;
};

}  // namespace hystbench::compensation
