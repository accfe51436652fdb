#pragma once
// Typed, range-checked parameters of a socket request (a JSON object): the one validator of the
// daemon's commands. Every check throws CommandError("bad_params", ...) naming the key and what
// was wrong; an absent key gives the fallback. Not real-time safe.
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

namespace hystbench::daemon::details {

/// What a parameter's value must be (request_params.cpp words them in this order).
enum class ParamType { kNumber, kInteger, kString, kObject, kArray, kBoolean };

/// One parameter of a command, the one place it is defined: key, type, the range a number or
/// integer must lie in (a range known only at run time, such as the loop rate's, is checked by
/// RequestParams::number's overloads), what it means and its default. The command table's rows
/// point at these, RequestParams reads requests through them, and docs/reference/protocol.md's
/// parameter tables are made from them (service/details/protocol_tables.hpp).
struct ParamSpec {
  const char* key;
  ParamType type;
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  /// What the key means, as the protocol page's table says it.
  const char* doc = "";
  /// The value an absent key takes when it is one constant: a number or integer as written,
  /// "true" or "false", a string as it is. The getters without a fallback return it.
  const char* fallback = nullptr;
  /// The default in words where it depends on the bench, the config or other keys (after
  /// `fallback` where both are given): the run builder passes that fallback itself.
  const char* fallback_doc = nullptr;
  /// Names the expected value in errors ("a number" and so on by default).
  const char* what = nullptr;
  /// Refuses the key with this reason (a key a client might expect, never accepted).
  const char* refusal = nullptr;
  /// The values a string takes, where the program lists them (the page adds them to `doc`).
  std::vector<std::string> (*values)() = nullptr;
};

/// A number's, integer's constant default (ParamSpec::fallback; std::logic_error without one).
double default_number(const ParamSpec& spec);

/// `params` is null or an object holding only listed keys, each of its type and in its range.
void check_params(const nlohmann::json& params, std::span<const ParamSpec> specs);

/// A request checked against its command's parameters at construction; the getters give a
/// key's value or the fallback when the key is absent. Keeps a reference to `params`.
class RequestParams {
 public:
  RequestParams(const nlohmann::json& params, std::span<const ParamSpec> specs);
  bool has(const char* key) const { return params_.is_object() && params_.contains(key); }
  /// The value, or the key's constant default (ParamSpec::fallback; a key without one is a
  /// programming error: std::logic_error).
  double number(const char* key) const;
  int integer(const char* key) const;
  std::string string(const char* key) const;
  bool boolean(const char* key) const;
  /// The value, or `fallback` (a default that depends on the bench: ParamSpec::fallback_doc).
  double number(const char* key, double fallback) const;
  /// Also within [lo, hi], a range that depends on the bench (limits, loop rate).
  double number(const char* key, double fallback, double lo, double hi) const;
  /// The value or its constant default, also within [lo, hi] (a range that depends on the bench).
  double number_within(const char* key, double lo, double hi) const;
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
