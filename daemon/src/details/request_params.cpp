#include "request_params.hpp"

#include <cmath>

#include "hystbench/daemon/command_error.hpp"

namespace hystbench::daemon::details {

using nlohmann::json;

void check_keys(const json& params, std::initializer_list<const char*> allowed) {
  if (params.is_null()) return;
  if (!params.is_object()) throw CommandError("bad_params", "params must be an object");
  for (const auto& [key, value] : params.items()) {
    bool ok = false;
    std::string list;
    for (const char* a : allowed) {
      ok = ok || key == a;
      list += (list.empty() ? "" : ", ") + std::string(a);
    }
    if (!ok)
      throw CommandError("bad_params", "unknown parameter '" + key + "' (valid: " + list + ")");
  }
}

double number_param(const json& params, const char* key, double fallback, double lo, double hi) {
  if (params.is_null() || !params.contains(key)) return fallback;
  const json& v = params[key];
  if (!v.is_number()) {
    throw CommandError("bad_params", std::string(key) + ": must be a number, got " + v.type_name());
  }
  const double d = v.get<double>();
  if (!std::isfinite(d) || d < lo || d > hi) {
    throw CommandError("bad_params", std::string(key) + ": " + std::to_string(d) +
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
    throw CommandError("bad_params", std::string(key) + ": must be an integer");
  }
  // Unsigned values beyond long long's range are out of range too, never wrapped.
  if (v.is_number_unsigned() && v.get<unsigned long long>() > static_cast<unsigned long long>(hi)) {
    throw CommandError("bad_params", std::string(key) + ": " + v.dump() + " is out of range [" +
                                         std::to_string(lo) + ", " + std::to_string(hi) + "]");
  }
  const auto d = v.get<long long>();
  if (d < lo || d > hi) {
    throw CommandError("bad_params", std::string(key) + ": " + std::to_string(d) +
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
    throw CommandError("bad_params", std::string(key) + ": must be a string");
  return params[key].get<std::string>();
}

}  // namespace hystbench::daemon::details
