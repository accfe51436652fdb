// The replaced global operator new of a test executable: it counts the allocations of a thread
// that asked (allocation_counter.hpp) and otherwise behaves as the standard one.
#include "support/allocation_counter.hpp"

#include <cstdlib>
#include <new>

namespace {
thread_local bool counting = false;
thread_local long allocations = 0;
}  // namespace

namespace hystbench::test {
void start_counting() noexcept {
  allocations = 0;
  counting = true;
}
long stop_counting() noexcept {
  counting = false;
  return allocations;
}
}  // namespace hystbench::test

// GCC pairs the replaced operator new with free() here and warns; they match.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmismatched-new-delete"
void* operator new(std::size_t size) {
  if (counting) ++allocations;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
#pragma GCC diagnostic pop
