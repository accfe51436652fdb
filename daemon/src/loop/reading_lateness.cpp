#include "hystbench/daemon/loop/reading_lateness.hpp"

#include <algorithm>

namespace hystbench::daemon {

void ReadingLateness::reset() noexcept {
  responses_.fill(0);
  usual_ = 0;
}

std::uint64_t ReadingLateness::late_ticks(std::uint64_t response_ticks) noexcept {
  const std::uint64_t r = std::min(response_ticks, kResponses - 1);
  ++responses_[r];
  if (responses_[r] > responses_[usual_] || (responses_[r] == responses_[usual_] && r < usual_)) {
    usual_ = r;
  }
  return response_ticks > usual_ ? response_ticks - usual_ : 0;
}

}  // namespace hystbench::daemon
