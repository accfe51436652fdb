#pragma once
// Reading a driver's JSON config table with messages that name the key path, e.g.
//   driver.modbus.output.format: unknown 'u64' (u16, s16, u32, s32)
// Not real-time: allocates and throws ParamError. Callers turn ParamError into a Result.
#include <cstdint>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

namespace hystbench::drivers::details {

class ParamError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// One table of parameters at `path` ("driver.modbus"); null is an empty table.
class Params {
 public:
  Params(const nlohmann::json& table, std::string path);

  /// Throws when a key is not in `allowed`, naming it and listing the valid ones.
  void allow_only(std::initializer_list<const char*> allowed) const;
  bool has(const char* key) const { return table_.contains(key); }
  std::string key_path(const char* key) const { return path_ + "." + key; }
  const std::string& path() const { return path_; }

  double number(const char* key, double fallback, double lo, double hi) const;
  std::int64_t integer(const char* key, std::int64_t fallback, std::int64_t lo,
                       std::int64_t hi) const;
  bool boolean(const char* key, bool fallback) const;
  std::string string(const char* key, const std::string& fallback) const;
  /// A string that must be one of `choices`.
  std::string choice(const char* key, const std::string& fallback,
                     std::initializer_list<const char*> choices) const;
  /// An array of integers, each in [lo, hi].
  std::vector<std::int64_t> integers(const char* key, std::vector<std::int64_t> fallback,
                                     std::int64_t lo, std::int64_t hi) const;
  /// An array of strings.
  std::vector<std::string> strings(const char* key, std::vector<std::string> fallback) const;
  /// A stage's axis names: 1 to kMaxAxes strings, each sim::is_axis_name, none twice (empty
  /// when absent: one axis).
  std::vector<std::string> axis_names(const char* key) const;
  /// A sub-table (empty when absent); throws when the key holds something else.
  Params table(const char* key) const;

 private:
  const nlohmann::json* get(const char* key) const;
  nlohmann::json table_;
  std::string path_;
};

}  // namespace hystbench::drivers::details
