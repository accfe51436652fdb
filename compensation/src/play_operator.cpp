#include "hystbench/compensation/play_operator.hpp"

#include "details/validate.hpp"

namespace hystbench::compensation {

PlayOperator::PlayOperator(double threshold, double initial_output)
    : r_(threshold), y_(initial_output) {
  details::require_finite(threshold, "threshold");
  details::require(threshold >= 0.0, "threshold must be >= 0");
  details::require_finite(initial_output, "initial_output");
}

}  // namespace hystbench::compensation
