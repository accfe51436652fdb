#pragma once
// Logarithmic creep as stage vendors state it: after a step of the displacement, the output keeps
// moving by gamma of the step per decade of time,
//   y(t) = y0 (1 + gamma log10(1 + t / t_ref)),   t_ref = 0.1 s,
// which for t >> t_ref is the vendors' y0 (1 + gamma log10(t / 0.1 s)) (within 0.04 gamma from
// 1 s on), y0 the displacement the static map gives at once. The log kernel has no finite state;
// it is realised as a dense bank of first-order lags, three per decade from t_ref / 30 to
// `longest_s`, whose weights are fitted (non-negative least squares) to the kernel: within
// 0.5 % of gamma over [0, longest_s], levelling off within a few times longest_s. The bank acts on
// the displacement, not on the input: the creep follows the hysteresis.
// Not real-time: called at construction.
#include "hystbench/compensation/creep_operator_bank.hpp"

namespace hystbench::sim {

/// The lag bank (time constants [s], gains per unit displacement) whose step response is
/// gamma * log10(1 + t / reference_s) up to longest_s. gamma in [0, 1);
/// 0 < 10 reference_s <= longest_s. Throws std::invalid_argument naming the argument.
compensation::CreepParameters logarithmic_creep_bank(double gamma, double longest_s,
                                                     double reference_s = 0.1);

}  // namespace hystbench::sim
