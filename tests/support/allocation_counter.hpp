#pragma once
// Counts the heap allocations a piece of code makes on the calling thread, for the real-time
// safety tests. A test executable that includes this header gets the counting global
// operator new of allocation_counter.cpp (add that file to its sources).
#include <utility>

namespace hystbench::test {

/// Allocations counted on this thread since the last start_counting(); counting on.
void start_counting() noexcept;
/// Stops counting on this thread and returns how many allocations it saw.
long stop_counting() noexcept;

/// The number of allocations f makes on this thread.
template <class F>
long allocations_during(F&& f) {
  start_counting();
  std::forward<F>(f)();
  return stop_counting();
}

}  // namespace hystbench::test
