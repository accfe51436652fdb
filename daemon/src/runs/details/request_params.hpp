#pragma once
// Typed, range-checked parameters of a socket request (a JSON object): the one validator of the
// daemon's commands. Every check throws CommandError("bad_params", ...) naming the key and what
// was wrong; an absent key gives the fallback. Not real-time safe.
#include <initializer_list>
#include <limits>
#include <nlohmann/json.hpp>
#include <span>
#include <string>

#include "hystbench/common/request_schema.hpp"

namespace hystbench::daemon::details {

// The schema of every request (hystbench/common/request_schema.hpp), shared with the CLI.
using common::default_number;
using common::ParamSpec;
using common::ParamType;

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
