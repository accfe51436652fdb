#include "details/json_params.hpp"

#include <cmath>
#include <set>

#include "hystbench/compensation/number_text.hpp"
#include "hystbench/drivers/driver_interface.hpp"
#include "hystbench/sim/simulated_stage_config.hpp"

namespace hystbench::drivers::details {

namespace {
std::string join(std::initializer_list<const char*> names) {
  std::string out;
  for (const char* n : names) out += (out.empty() ? "" : ", ") + std::string(n);
  return out;
}
}  // namespace

Params::Params(const nlohmann::json& table, std::string path) : path_(std::move(path)) {
  if (table.is_null()) {
    table_ = nlohmann::json::object();
  } else if (table.is_object()) {
    table_ = table;
  } else {
    throw ParamError(path_ + ": must be a table, got " + table.type_name());
  }
}

void Params::allow_only(std::initializer_list<const char*> allowed) const {
  for (const auto& [key, value] : table_.items()) {
    bool ok = false;
    for (const char* a : allowed) ok = ok || key == a;
    if (!ok) throw ParamError(path_ + "." + key + ": unknown key (" + join(allowed) + ")");
  }
}

const nlohmann::json* Params::get(const char* key) const {
  auto it = table_.find(key);
  return it == table_.end() ? nullptr : &*it;
}

double Params::number(const char* key, double fallback, double lo, double hi) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_number()) {
    throw ParamError(key_path(key) + ": must be a number, got " + v->type_name());
  }
  const double d = v->get<double>();
  if (!std::isfinite(d) || d < lo || d > hi) {
    throw ParamError(key_path(key) + ": must be in [" + compensation::significant(lo, 6) + ", " +
                     compensation::significant(hi, 6) + "], got " +
                     compensation::significant(d, 6));
  }
  return d;
}

std::int64_t Params::integer(const char* key, std::int64_t fallback, std::int64_t lo,
                             std::int64_t hi) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_number_integer()) {
    throw ParamError(key_path(key) + ": must be an integer, got " + v->dump());
  }
  const std::int64_t i = v->get<std::int64_t>();
  if (i < lo || i > hi) {
    throw ParamError(key_path(key) + ": must be in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "], got " + std::to_string(i));
  }
  return i;
}

bool Params::boolean(const char* key, bool fallback) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_boolean()) throw ParamError(key_path(key) + ": must be true or false");
  return v->get<bool>();
}

std::string Params::string(const char* key, const std::string& fallback) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_string()) {
    throw ParamError(key_path(key) + ": must be a string, got " + v->type_name());
  }
  return v->get<std::string>();
}

std::string Params::choice(const char* key, const std::string& fallback,
                           std::initializer_list<const char*> choices) const {
  std::string s = string(key, fallback);
  for (const char* c : choices) {
    if (s == c) return s;
  }
  throw ParamError(key_path(key) + ": unknown '" + s + "' (" + join(choices) + ")");
}

std::vector<std::int64_t> Params::integers(const char* key, std::vector<std::int64_t> fallback,
                                           std::int64_t lo, std::int64_t hi) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_array()) throw ParamError(key_path(key) + ": must be an array of integers");
  std::vector<std::int64_t> out;
  for (const auto& e : *v) {
    if (!e.is_number_integer() || e.get<std::int64_t>() < lo || e.get<std::int64_t>() > hi) {
      throw ParamError(key_path(key) + ": every element must be an integer in [" +
                       std::to_string(lo) + ", " + std::to_string(hi) + "], got " + e.dump());
    }
    out.push_back(e.get<std::int64_t>());
  }
  return out;
}

std::vector<std::string> Params::strings(const char* key, std::vector<std::string> fallback) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return fallback;
  if (!v->is_array()) throw ParamError(key_path(key) + ": must be an array of strings");
  std::vector<std::string> out;
  for (const auto& e : *v) {
    if (!e.is_string()) {
      throw ParamError(key_path(key) + ": every element must be a string, got " + e.dump());
    }
    out.push_back(e.get<std::string>());
  }
  return out;
}

std::vector<std::string> Params::axis_names(const char* key) const {
  std::vector<std::string> names = strings(key, {});
  if (has(key) && (names.empty() || names.size() > kMaxAxes)) {
    throw ParamError(key_path(key) + ": 1 to " + std::to_string(kMaxAxes) + " axis names, got " +
                     std::to_string(names.size()));
  }
  std::set<std::string> seen;
  for (const std::string& name : names) {
    if (!sim::is_axis_name(name)) {
      throw ParamError(key_path(key) + ": \"" + name + "\": 1 to 16 of a-z, 0-9 and _");
    }
    if (!seen.insert(name).second) {
      throw ParamError(key_path(key) + ": \"" + name + "\" names two axes");
    }
  }
  return names;
}

Params Params::table(const char* key) const {
  const nlohmann::json* v = get(key);
  if (v == nullptr) return Params(nlohmann::json::object(), key_path(key));
  return Params(*v, key_path(key));
}

}  // namespace hystbench::drivers::details
