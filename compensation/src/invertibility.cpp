#include "hystbench/compensation/invertibility.hpp"

namespace hystbench::compensation {

Invertibility check_cumulative_weights(const double* weights, std::size_t n,
                                       const std::string& block, const std::string& label,
                                       double rate, const double* rate_slopes) {
  double cumulative = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    cumulative += weights[i] + (rate_slopes != nullptr ? rate_slopes[i] * rate : 0.0);
    if (!(cumulative > 0.0)) {
      return Invertibility::failure(
          block, static_cast<int>(i), cumulative,
          label + " W[" + std::to_string(i) + "]" +
              (rate_slopes != nullptr ? " at rate " + std::to_string(rate) : std::string()) +
              " = " + std::to_string(cumulative) +
              " is not positive (the loading curve is not increasing there)");
    }
  }
  return Invertibility::ok();
}

}  // namespace hystbench::compensation
