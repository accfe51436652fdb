#pragma once
// Reading a model file's JSON fields: each check throws ModelFileError naming the field
// ("play.thresholds[3]: must be finite"). For model_file.cpp and stage_responses.cpp.
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "hystbench/compensation/model_file.hpp"

namespace hystbench::compensation::details {

[[noreturn]] inline void fail(const std::string& field, const std::string& what) {
  throw ModelFileError(field + ": " + what);
}

/// obj[key]; `parent` names obj ("" for the top level).
inline const nlohmann::json& member(const nlohmann::json& obj, const std::string& parent,
                                    const char* key) {
  const std::string field = parent.empty() ? key : parent + "." + key;
  if (!obj.is_object()) fail(parent.empty() ? "(top level)" : parent, "must be an object");
  const auto it = obj.find(key);
  if (it == obj.end()) fail(field, "missing");
  return *it;
}

/// A finite number.
inline double number(const nlohmann::json& v, const std::string& field) {
  if (!v.is_number()) fail(field, std::string("must be a number, got ") + v.type_name());
  const double d = v.get<double>();
  if (!std::isfinite(d)) fail(field, "must be finite");
  return d;
}

/// obj[key], an array of finite numbers.
inline std::vector<double> numbers(const nlohmann::json& obj, const std::string& parent,
                                   const char* key) {
  const nlohmann::json& v = member(obj, parent, key);
  const std::string field = parent + "." + key;
  // NaN is not valid JSON; a null in an array (what many tools write for NaN) is caught here.
  if (!v.is_array()) fail(field, std::string("must be an array of numbers, got ") + v.type_name());
  std::vector<double> out;
  out.reserve(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) {
    out.push_back(number(v[i], field + "[" + std::to_string(i) + "]"));
  }
  return out;
}

}  // namespace hystbench::compensation::details
