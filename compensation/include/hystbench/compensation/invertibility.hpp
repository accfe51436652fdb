#pragma once
// Result of an invertibility check, and the error thrown when an inverse is requested anyway.
#include <cstddef>
#include <stdexcept>
#include <string>

namespace hystbench::compensation {

struct Invertibility {
  bool invertible = true;
  /// Which parameter block failed ("play", "deadzone", "rate", ...) and the offending index.
  std::string block;
  int index = -1;
  /// The offending cumulative weight (or other value) and a sentence for the user.
  double value = 0.0;
  std::string reason;

  static Invertibility ok() { return {}; }
  static Invertibility failure(std::string block, int index, double value, std::string reason) {
    return {false, std::move(block), index, value, std::move(reason)};
  }
};

/// Checks that the running sums of `weights` (the slopes of a loading curve) stay positive;
/// names the first index where one does not, as "<label> W[i] = ... is not positive".
Invertibility check_cumulative_weights(const double* weights, std::size_t n,
                                       const std::string& block, const std::string& label,
                                       double rate = 0.0, const double* rate_slopes = nullptr);

class NotInvertibleError : public std::runtime_error {
 public:
  explicit NotInvertibleError(const Invertibility& why)
      : std::runtime_error("model is not invertible: " + why.reason), why_(why) {}
  const Invertibility& why() const noexcept { return why_; }

 private:
  Invertibility why_;
};

}  // namespace hystbench::compensation
