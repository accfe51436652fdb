#include "hystbench/daemon/loop/output_history.hpp"

#include <algorithm>
#include <stdexcept>

namespace hystbench::daemon {

OutputHistory::OutputHistory(std::size_t capacity)
    : capacity_(capacity), slots_(std::make_unique<std::atomic<double>[]>(capacity)) {
  if (capacity == 0) throw std::invalid_argument("output history: capacity must be >= 1");
}

std::uint64_t OutputHistory::copy_since(std::uint64_t from, std::vector<double>& out) const {
  const std::uint64_t end = written();
  const std::uint64_t oldest = end > capacity_ ? end - capacity_ : 0;
  std::uint64_t first = std::clamp(from, oldest, end);
  out.resize(static_cast<std::size_t>(end - first));
  for (std::uint64_t t = first; t < end; ++t) {
    out[static_cast<std::size_t>(t - first)] =
        slots_[t % capacity_].load(std::memory_order_relaxed);
  }
  // The loop went on meanwhile: the ticks it has overwritten since, and the one it may be
  // writing now (tick `now`, in the slot of now - capacity), are not the ones copied.
  std::atomic_thread_fence(std::memory_order_acquire);
  const std::uint64_t now = written() + 1;
  const std::uint64_t kept_from = now > capacity_ ? now - capacity_ : 0;
  if (kept_from > first) {
    const auto lost = static_cast<std::ptrdiff_t>(std::min(kept_from, end) - first);
    out.erase(out.begin(), out.begin() + lost);
    first += static_cast<std::uint64_t>(lost);
  }
  return first;
}

}  // namespace hystbench::daemon
