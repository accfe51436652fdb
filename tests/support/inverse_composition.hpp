#pragma once
// How well an inverse composes with its model: the model driven by the inverse's drive for a
// reference, its largest error after the first fifth of the reference (the start from rest left
// out), as a share of the reference's largest excursion from its first sample.
#include <algorithm>
#include <cmath>
#include <vector>

#include "hystbench/compensation/actuator_model.hpp"
#include "hystbench/compensation/inverse_model.hpp"

namespace hystbench::testing {

/// The inverse and a copy of the model both start at rest at u0.
inline double worst_composed_error(const compensation::ActuatorModel& model,
                                   compensation::InverseModel& inverse,
                                   const std::vector<double>& ref, double u0) {
  inverse.reset(u0);
  const std::vector<double> drive = compensation::invert_sequence(inverse, ref);
  compensation::ActuatorModel check = model;
  check.reset(u0);
  double worst = 0.0, span = 0.0;
  for (std::size_t k = 0; k < ref.size(); ++k) {
    const double y = check.step(drive[k]);
    if (k > ref.size() / 5) worst = std::max(worst, std::abs(y - ref[k]));
    span = std::max(span, std::abs(ref[k] - ref[0]));
  }
  return worst / span;
}

}  // namespace hystbench::testing
