#pragma once
// toml++ nodes to nlohmann::json (the converter behind toml_to_json() and the raw [driver.*] /
// [actuator] tables of the configuration).
#include <toml++/toml.h>

#include <nlohmann/json.hpp>

namespace hystbench::daemon::details {

/// Tables -> objects, arrays -> arrays, integers -> uint64 (>= 0) or int64, floats -> double,
/// booleans, and dates / times / date-times -> their TOML (ISO 8601) text.
nlohmann::json toml_node_to_json(const toml::node& node);

/// "table", "array", "string", "integer", "float", "boolean", "date", "time", "date-time".
const char* toml_type_name(const toml::node& node) noexcept;

}  // namespace hystbench::daemon::details
