#pragma once
// The feedforward targets of this tick and of the ticks ahead, for an inverse that looks ahead
// (compensation::InverseModel::preview_samples). allocate() is for the control thread; push(),
// view() and clear() are real-time safe (one value in per tick, amortised O(1): the window is
// moved to the front of its buffer once every capacity() ticks).
#include <algorithm>
#include <cstddef>
#include <span>
#include <vector>

namespace hystbench::daemon {

class TargetWindow {
 public:
  /// Room for `samples` targets (0: no look-ahead); empties the window.
  void allocate(std::size_t samples) {
    capacity_ = samples;
    buffer_.assign(2 * samples, 0.0);
    clear();
  }
  std::size_t capacity() const noexcept { return capacity_; }
  void clear() noexcept { begin_ = size_ = 0; }
  /// Appends the newest target, dropping the oldest when the window is full.
  void push(double target) noexcept {
    if (capacity_ == 0) return;
    if (size_ == capacity_) {
      ++begin_;
      --size_;
    }
    if (begin_ + size_ == buffer_.size()) {
      std::copy_n(buffer_.begin() + static_cast<std::ptrdiff_t>(begin_), size_, buffer_.begin());
      begin_ = 0;
    }
    buffer_[begin_ + size_++] = target;
  }
  /// Oldest (this tick's) first.
  std::span<const double> view() const noexcept { return {buffer_.data() + begin_, size_}; }
  /// One tick at run time t_s [s], ticks dt_s [s] apart: an empty window is first filled with
  /// target_at(t_s + j dt_s) for the capacity() - 1 ticks before the newest, then the target
  /// capacity() - 1 ticks ahead is pushed. Returns view(). target_at must be noexcept.
  template <class TargetAt>
  std::span<const double> advance(double t_s, double dt_s, TargetAt&& target_at) noexcept {
    if (size_ == 0) {
      for (std::size_t j = 0; j + 1 < capacity_; ++j)
        push(target_at(t_s + static_cast<double>(j) * dt_s));
    }
    push(target_at(t_s + static_cast<double>(capacity_ - 1) * dt_s));
    return view();
  }

 private:
  std::vector<double> buffer_;
  std::size_t capacity_ = 0, begin_ = 0, size_ = 0;
};

}  // namespace hystbench::daemon
