#pragma once
// A command refused by the bench: a machine-readable code ("bad_params", "busy", "no_model",
// "out_of_range", ...), a message in words, and optional details that the reply's error object
// carries as extra keys (e.g. {"sample": 1234} for the first offending sample of an upload).
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>

namespace hystbench::common {

class CommandError : public std::runtime_error {
 public:
  CommandError(std::string code, const std::string& message,
               nlohmann::json detail = nlohmann::json::object())
      : std::runtime_error(message), code_(std::move(code)), detail_(std::move(detail)) {}
  const std::string& code() const noexcept { return code_; }
  /// Extra keys of the error object (an object, possibly empty).
  const nlohmann::json& detail() const noexcept { return detail_; }

 private:
  std::string code_;
  nlohmann::json detail_;
};

}  // namespace hystbench::common
