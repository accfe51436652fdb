#pragma once
// Typed, range-checked parameters of a socket request (a JSON object): the one validator of the
// daemon's commands. Every check throws CommandError("bad_params", ...) naming the key and what
// was wrong; an absent key gives the fallback. Not real-time safe.
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

namespace hystbench::daemon::details {

/// What a parameter's value must be (request_params.cpp words them in this order).
enum class ParamType { kNumber, kInteger, kString, kObject, kArray, kBoolean };

/// One parameter of a command: key, type and the range a number or integer must lie in (a
/// range known only at run time, such as the loop rate's, is checked by RequestParams::number's
/// overload). `what` names the expected value in errors ("a number" and so on by default);
/// `refusal` refuses the key with that reason (a key a client might expect, never accepted).
struct ParamSpec {
  const char* key;
  ParamType type;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  const char* what = nullptr;
  const char* refusal = nullptr;
};

/// `params` is null or an object holding only listed keys, each of its type and in its range.
void check_params(const nlohmann::json& params, std::span<const ParamSpec> specs);

/// A request checked against its command's parameters at construction; the getters give a
/// key's value or the fallback when the key is absent. Keeps a reference to `params`.
class RequestParams {
 public:
  RequestParams(const nlohmann::json& params, std::span<const ParamSpec> specs);
  bool has(const char* key) const { return params_.is_object() && params_.contains(key); }
  double number(const char* key, double fallback) const;
  /// Also within [lo, hi], a range that depends on the bench (limits, loop rate).
  double number(const char* key, double fallback, double lo, double hi) const;
  int integer(const char* key, int fallback) const;
  std::string string(const char* key, const std::string& fallback) const;
  bool boolean(const char* key, bool fallback) const;
  const nlohmann::json& params() const { return params_; }

 private:
  const ParamSpec& spec(const char* key) const;
  const nlohmann::json& params_;
  std::span<const ParamSpec> specs_;
};

/// `params` must be null or an object holding only the listed keys.
void check_keys(const nlohmann::json& params, std::initializer_list<const char*> allowed);
/// A finite number in [lo, hi].
double number_param(const nlohmann::json& params, const char* key, double fallback, double lo,
                    double hi);
/// An integer in [lo, hi].
long long integer_param(const nlohmann::json& params, const char* key, long long fallback,
                        long long lo, long long hi);
int int_param(const nlohmann::json& params, const char* key, int fallback, int lo, int hi);
std::string string_param(const nlohmann::json& params, const char* key,
                         const std::string& fallback);

}  // namespace hystbench::daemon::details
