#pragma once
// Typed, range-checked parameters of a socket request (a JSON object). Every check throws
// CommandError("bad_params", ...) naming the key and what was wrong; an absent key gives the
// fallback. Not real-time safe.
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon::details {

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
