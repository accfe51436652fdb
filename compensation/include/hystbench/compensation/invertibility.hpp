#pragma once
// Result of an invertibility check, and the error thrown when an inverse is requested anyway.
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
};

class NotInvertibleError : public std::runtime_error {
 public:
  explicit NotInvertibleError(const Invertibility& why)
      : std::runtime_error("model is not invertible: " + why.reason), why_(why) {}
  const Invertibility& why() const noexcept { return why_; }

 private:
  Invertibility why_;
};

}  // namespace hystbench::compensation
