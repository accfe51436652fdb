#pragma once
// How much a stage's axes' loops, each designed alone, disturb each other through the coupling:
// generalized diagonal dominance (Grosdidier and Morari). With G(f) the stage's measured
// response matrix (G_ij: axis j's drive to axis i's output) and each axis's loop designed on
// G_ii, the loops are stable together when each is stable alone and, at every frequency,
//   rho(E(f) T(f)) < 1,  E = (G - diag G) (diag G)^-1  (E_ij = G_ij / G_jj),
//   T = diag(L_i / (1 + L_i)),  L_i each axis's own loop;
// rho is the spectral radius. The margin to 1 says how much more coupling the loops would bear.
// E is a ratio of responses in the same units, so the loop's own plant (through the inverse) and
// the raw measurement give the same E. Pure maths; allocates: not real-time.
#include <complex>
#include <cstddef>
#include <vector>

#include "hystbench/compensation/measured_response.hpp"

namespace hystbench::compensation {

struct StageInteraction {
  /// rho(E T) at each frequency_hz (the lines every response of the stage shares).
  std::vector<double> frequency_hz, spectral_radius;
  double peak = 0.0;     ///< the largest spectral radius
  double peak_hz = 0.0;  ///< where it falls [Hz]
  /// peak < 1: the loops stay stable together (sufficient, not necessary).
  bool dominant() const noexcept { return peak < 1.0; }
};

/// `g[i][j]`: the response of axis i's output to axis j's drive, all measured at the same lines
/// (square, n >= 2, each of g[i][i]'s lines); `loops[i]`: axis i's loop L_i at those lines.
/// Lines where a response's frequency differs are left out. Throws std::invalid_argument for a
/// non-square g, a loops count other than n, or no line every response shares.
StageInteraction stage_interaction(const std::vector<std::vector<MeasuredResponse>>& g,
                                   const std::vector<std::vector<std::complex<double>>>& loops);

}  // namespace hystbench::compensation
