#include "hystbench/daemon/loop/reading_lateness.hpp"

#include <algorithm>

namespace hystbench::daemon {

void ReadingLateness::reset() noexcept {
  responses_.fill(0);
  gaps_.fill(0);
  usual_response_ = 0;
  usual_gap_ = 1;
  stale_run_ = 0;
  holding_ = 0;
}

void ReadingLateness::count(Counts& counts, std::uint64_t& usual, std::uint64_t value) noexcept {
  const std::uint64_t v = std::min(value, kCounted - 1);
  ++counts[v];
  if (counts[v] > counts[usual] || (counts[v] == counts[usual] && v < usual)) usual = v;
}

ReadingLateness::Fresh ReadingLateness::fresh(std::uint64_t response_ticks) noexcept {
  const std::uint64_t gap = stale_run_ + 1;
  stale_run_ = 0;
  count(responses_, usual_response_, response_ticks);
  count(gaps_, usual_gap_, gap);
  if (gap >= usual_gap_ + 2) holding_ = std::max(holding_, gap - usual_gap_);
  Fresh f;
  f.late_ticks = response_ticks > usual_response_ ? response_ticks - usual_response_ : 0;
  if (holding_ > 0) {
    --holding_;
    f.hold = true;
  }
  return f;
}

}  // namespace hystbench::daemon
