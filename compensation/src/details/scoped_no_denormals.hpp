#pragma once
// Subnormal doubles flushed to zero on this thread while the guard lives (internals). A filter
// state that decays towards zero (a lightly damped mode filtering a regressor column that went
// quiet) spends thousands of samples in the subnormal range, where each multiply costs the
// processor a microcode assist; flushed, those values are zero. Results change by less than the
// smallest normal double (2.2e-308). Real-time safe; restores the thread's previous mode.
// Held by ScopedNoDenormals.FlushesASubnormalProductToZeroAndRestores (tests/compensation).
#if defined(__SSE2__)
#include <xmmintrin.h>
#endif

namespace hystbench::compensation::details {

class ScopedNoDenormals {
 public:
#if defined(__SSE2__)
  // MXCSR bit 15 flushes subnormal results to zero (FTZ), bit 6 reads subnormal inputs as zero
  // (DAZ).
  static constexpr unsigned kFlushBits = 0x8040U;
  ScopedNoDenormals() noexcept : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushBits); }
  ~ScopedNoDenormals() { _mm_setcsr(saved_); }
#else
  ScopedNoDenormals() noexcept = default;  // elsewhere the fits run at the default mode
#endif
  ScopedNoDenormals(const ScopedNoDenormals&) = delete;
  ScopedNoDenormals& operator=(const ScopedNoDenormals&) = delete;

 private:
#if defined(__SSE2__)
  unsigned saved_;
#endif
};

}  // namespace hystbench::compensation::details
