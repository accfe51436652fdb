#pragma once
// The hot loops of the PI-family models: update every play operator for one input sample and
// return the weighted sum of their outputs. Real-time safe (no allocation, no exceptions),
// O(n). On x86-64 with GCC each is compiled for AVX2 and for the baseline and the loader picks
// the one the CPU runs; both add in the same order, so their results are identical.
#include <cstddef>

namespace hystbench::compensation::details {

/// Classical play: s_i = max(u - r_i, min(u + r_i, s_i)); returns sum_i w_i s_i.
double play_step(double u, const double* r, const double* w, double* s, std::size_t n) noexcept;

/// The coupled-play operators' thresholds and weights, n of each.
struct CoupledPlayArrays {
  const double *r, *ra, *rb, *rc, *w;
  std::size_t n;
};

/// Coupled-play operators (CoupledPlayPiModel) with one direction for all of them
/// (rising: u >= u_prev): z_i updated in place; returns sum_i w_i z_i.
double coupled_play_step(double u, bool rising, const CoupledPlayArrays& a, double* z) noexcept;

/// The same sum without changing z (what the next step would give).
double coupled_play_peek(double u, bool rising, const CoupledPlayArrays& a,
                         const double* z) noexcept;

}  // namespace hystbench::compensation::details
