#include "details/play_kernels.hpp"

namespace hystbench::compensation::details {

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
#define HYSTBENCH_KERNEL __attribute__((target_clones("avx2", "default")))
#else
#define HYSTBENCH_KERNEL
#endif

namespace {

// sum_i w_i x_i with four independent accumulators: without -ffast-math the compiler may not
// reorder a floating-point sum, and one serial accumulator makes the step latency-bound.
// Inlined into each kernel, so it is compiled for that kernel's target.
inline double weighted_sum(const double* w, const double* x, std::size_t n) noexcept {
  double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    a0 += w[i] * x[i];
    a1 += w[i + 1] * x[i + 1];
    a2 += w[i + 2] * x[i + 2];
    a3 += w[i + 3] * x[i + 3];
  }
  for (; i < n; ++i) a0 += w[i] * x[i];
  return (a0 + a1) + (a2 + a3);
}

// One coupled-play operator in the given direction; branch-free so the loop vectorises.
inline double coupled_play(double u, bool rising, double z, double r, double ra, double rb,
                           double rc) noexcept {
  const double rise_width = u >= rc ? r : rc;
  const double fall_width = u <= -rb ? ra : rb;
  const double up = u - rise_width, down = u + fall_width;
  const double rose = z > up ? z : up;
  const double fell = z < down ? z : down;
  return rising ? rose : fell;
}

}  // namespace

HYSTBENCH_KERNEL
double play_step(double u, const double* r, const double* w, double* s, std::size_t n) noexcept {
  for (std::size_t i = 0; i < n; ++i) {
    const double lo = u - r[i], hi = u + r[i];
    const double v = s[i] < hi ? s[i] : hi;  // min, max written out so they vectorise
    s[i] = v > lo ? v : lo;
  }
  return weighted_sum(w, s, n);
}

HYSTBENCH_KERNEL
double coupled_play_step(double u, bool rising, const CoupledPlayArrays& a, double* z) noexcept {
  for (std::size_t i = 0; i < a.n; ++i) {
    z[i] = coupled_play(u, rising, z[i], a.r[i], a.ra[i], a.rb[i], a.rc[i]);
  }
  return weighted_sum(a.w, z, a.n);
}

HYSTBENCH_KERNEL
double coupled_play_peek(double u, bool rising, const CoupledPlayArrays& a,
                         const double* z) noexcept {
  double a0 = 0.0, a1 = 0.0, a2 = 0.0, a3 = 0.0;
  std::size_t i = 0;
  auto term = [&](std::size_t k) {
    return a.w[k] * coupled_play(u, rising, z[k], a.r[k], a.ra[k], a.rb[k], a.rc[k]);
  };
  for (; i + 4 <= a.n; i += 4) {
    a0 += term(i);
    a1 += term(i + 1);
    a2 += term(i + 2);
    a3 += term(i + 3);
  }
  for (; i < a.n; ++i) a0 += term(i);
  return (a0 + a1) + (a2 + a3);
}

}  // namespace hystbench::compensation::details
