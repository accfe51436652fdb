#include "runs/details/request_params.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string_view>

#include "hystbench/common/command_error.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

namespace {

void check_object(const json& params) {
  if (!params.is_null() && !params.is_object()) {
    throw common::CommandError("bad_params", "params must be an object");
  }
}

[[noreturn]] void unknown_key(const std::string& key, const std::string& valid) {
  throw common::CommandError("bad_params",
                             "unknown parameter '" + key + "' (valid: " + valid + ")");
}

long long integer_bound(double v) {
  constexpr double kMax = 9.2e18;  // inside long long's range
  return static_cast<long long>(std::clamp(v, -kMax, kMax));
}

// What a value of each ParamType is called in errors, in the enum's order.
constexpr const char* kTypeWords[] = {"a number",  "an integer", "a string",
                                      "an object", "an array",   "true or false"};

// The value of params[spec.key] (present) against its spec.
void check_value(const json& params, const ParamSpec& spec) {
  if (spec.refusal != nullptr) {
    throw common::CommandError("bad_params", std::string(spec.key) + ": " + spec.refusal);
  }
  const json& v = params[spec.key];
  switch (spec.type) {
    case ParamType::kNumber:
      if (spec.what == nullptr || v.is_number()) {
        (void)number_param(params, spec.key, 0.0, spec.lo, spec.hi);
        return;
      }
      break;
    case ParamType::kInteger:
      if (spec.what == nullptr || v.is_number_integer()) {
        (void)integer_param(params, spec.key, 0, integer_bound(spec.lo), integer_bound(spec.hi));
        return;
      }
      break;
    case ParamType::kString:
      if (v.is_string()) return;
      break;
    case ParamType::kObject:
      if (v.is_object()) return;
      break;
    case ParamType::kArray:
      if (v.is_array()) return;
      break;
    case ParamType::kBoolean:
      if (v.is_boolean()) return;
      break;
  }
  throw common::CommandError(
      "bad_params",
      std::string(spec.key) + ": must be " +
          (spec.what != nullptr ? spec.what : kTypeWords[static_cast<int>(spec.type)]));
}

}  // namespace

void check_params(const json& params, std::span<const ParamSpec> specs) {
  check_object(params);
  if (params.is_null()) return;
  for (const auto& [key, value] : params.items()) {
    const ParamSpec* found = nullptr;
    std::string valid;
    for (const ParamSpec& s : specs) {
      if (key == s.key) found = &s;
      if (s.refusal == nullptr) valid += (valid.empty() ? "" : ", ") + std::string(s.key);
    }
    if (found == nullptr) unknown_key(key, valid);
    check_value(params, *found);
  }
}

RequestParams::RequestParams(const json& params, std::span<const ParamSpec> specs)
    : params_(params), specs_(specs) {
  check_params(params_, specs_);
}

const ParamSpec& RequestParams::spec(const char* key) const {
  for (const ParamSpec& s : specs_) {
    if (std::string_view(s.key) == key) return s;
  }
  throw std::logic_error(std::string("request parameter '") + key + "' is not in its command");
}

double RequestParams::number(const char* key) const {
  return number(key, default_number(spec(key)));
}

int RequestParams::integer(const char* key) const {
  return integer(key, static_cast<int>(default_number(spec(key))));
}

std::string RequestParams::string(const char* key) const {
  return string(key, std::string(common::default_constant(spec(key))));
}

bool RequestParams::boolean(const char* key) const {
  const std::string_view text = common::default_constant(spec(key));
  if (text != "true" && text != "false") {
    throw std::logic_error(std::string("request parameter '") + key + "': default '" +
                           std::string(text) + "' is not true or false");
  }
  return boolean(key, text == "true");
}

double RequestParams::number_within(const char* key, double lo, double hi) const {
  return number(key, default_number(spec(key)), lo, hi);
}

double RequestParams::number(const char* key, double fallback) const {
  const ParamSpec& s = spec(key);
  return number_param(params_, key, fallback, s.lo, s.hi);
}

double RequestParams::number(const char* key, double fallback, double lo, double hi) const {
  (void)spec(key);
  return number_param(params_, key, fallback, lo, hi);
}

int RequestParams::integer(const char* key, int fallback) const {
  const ParamSpec& s = spec(key);
  return static_cast<int>(
      integer_param(params_, key, fallback, integer_bound(s.lo), integer_bound(s.hi)));
}

std::string RequestParams::string(const char* key, const std::string& fallback) const {
  (void)spec(key);
  return string_param(params_, key, fallback);
}

bool RequestParams::boolean(const char* key, bool fallback) const {
  (void)spec(key);
  return has(key) ? params_[key].get<bool>() : fallback;
}

void check_keys(const json& params, std::initializer_list<const char*> allowed) {
  check_object(params);
  if (params.is_null()) return;
  for (const auto& [key, value] : params.items()) {
    bool ok = false;
    std::string list;
    for (const char* a : allowed) {
      ok = ok || key == a;
      list += (list.empty() ? "" : ", ") + std::string(a);
    }
    if (!ok) unknown_key(key, list);
  }
}

double number_param(const json& params, const char* key, double fallback, double lo, double hi) {
  if (params.is_null() || !params.contains(key)) return fallback;
  const json& v = params[key];
  if (!v.is_number()) {
    throw common::CommandError("bad_params",
                               std::string(key) + ": must be a number, got " + v.type_name());
  }
  const double d = v.get<double>();
  if (!std::isfinite(d) || d < lo || d > hi) {
    throw common::CommandError("bad_params", std::string(key) + ": " + std::to_string(d) +
                                                 " is out of range [" + std::to_string(lo) + ", " +
                                                 std::to_string(hi) + "]");
  }
  return d;
}

long long integer_param(const json& params, const char* key, long long fallback, long long lo,
                        long long hi) {
  if (params.is_null() || !params.contains(key)) return fallback;
  const json& v = params[key];
  if (!v.is_number_integer()) {
    throw common::CommandError("bad_params", std::string(key) + ": must be an integer");
  }
  // Unsigned values beyond long long's range are out of range too, never wrapped.
  if (v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(hi)) {
    throw common::CommandError("bad_params", std::string(key) + ": " + v.dump() +
                                                 " is out of range [" + std::to_string(lo) + ", " +
                                                 std::to_string(hi) + "]");
  }
  const auto d = v.get<long long>();
  if (d < lo || d > hi) {
    throw common::CommandError("bad_params", std::string(key) + ": " + std::to_string(d) +
                                                 " is out of range [" + std::to_string(lo) + ", " +
                                                 std::to_string(hi) + "]");
  }
  return d;
}

int int_param(const json& params, const char* key, int fallback, int lo, int hi) {
  return static_cast<int>(integer_param(params, key, fallback, lo, hi));
}

std::string string_param(const json& params, const char* key, const std::string& fallback) {
  if (params.is_null() || !params.contains(key)) return fallback;
  if (!params[key].is_string())
    throw common::CommandError("bad_params", std::string(key) + ": must be a string");
  return params[key].get<std::string>();
}

}  // namespace hystbench::daemon::details
