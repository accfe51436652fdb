#include "hystbench/compensation/period_average.hpp"

#include <cmath>
#include <numeric>

#include "details/validate.hpp"

namespace hystbench::compensation {

PeriodAverage::PeriodAverage(double period_samples) {
  details::require(std::isfinite(period_samples) && period_samples >= 0.0,
                   "the averaging period must be finite and >= 0 samples");
  if (period_samples < 1.0) return;
  const double whole = std::floor(period_samples);
  fraction_ = period_samples - whole;
  length_ = period_samples;
  buf_.assign(static_cast<std::size_t>(whole) + 1, 0.0);
}

double PeriodAverage::step(double x) noexcept {
  if (buf_.empty()) return x;
  const std::size_t m = buf_.size();
  std::size_t next = head_ + 1;
  if (next == m) next = 0;
  // buf_[next] is the window's oldest sample; it leaves the whole-sample window and becomes the
  // fractional one, whose slot x overwrites.
  sum_ += x - buf_[next];
  buf_[head_] = x;
  head_ = next;
  if (head_ == 0) {  // once a period: no rounding drift in the running sum
    sum_ = std::accumulate(buf_.begin(), buf_.end(), 0.0) - buf_[head_];
  }
  return (sum_ + fraction_ * buf_[head_]) / length_;
}

void PeriodAverage::reset() noexcept {
  for (double& v : buf_) v = 0.0;
  head_ = 0;
  sum_ = 0.0;
}

}  // namespace hystbench::compensation
