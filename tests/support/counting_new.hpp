#pragma once
// Counts heap allocations, for tests that a real-time path allocates nothing. Defines the global
// operator new and delete: include it in exactly one .cpp of a test executable.
// allocations_during(f) counts what f() allocates on the calling thread (other threads, such as
// an I/O thread or a peer, are not counted).
#include <cstdlib>
#include <new>

namespace hystbench::test {

inline thread_local bool counting_allocations = false;
inline thread_local long allocations_counted = 0;

/// The allocations f() makes on this thread.
template <class F>
long allocations_during(F&& f) {
  allocations_counted = 0;
  counting_allocations = true;
  f();
  counting_allocations = false;
  return allocations_counted;
}

}  // namespace hystbench::test

void* operator new(std::size_t size) {
  if (hystbench::test::counting_allocations) ++hystbench::test::allocations_counted;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
