#include "config/details/toml_json.hpp"

#include <cstdint>
#include <sstream>

namespace hystbench::daemon::details {

namespace {

template <typename T>
std::string text_of(const T& value) {
  std::ostringstream out;
  out << value;
  return out.str();
}

}  // namespace

nlohmann::json toml_node_to_json(const toml::node& node) {
  switch (node.type()) {
    case toml::node_type::table: {
      nlohmann::json object = nlohmann::json::object();
      for (const auto& [key, value] : *node.as_table()) {
        object[std::string(key.str())] = toml_node_to_json(value);
      }
      return object;
    }
    case toml::node_type::array: {
      nlohmann::json array = nlohmann::json::array();
      for (const auto& element : *node.as_array()) array.push_back(toml_node_to_json(element));
      return array;
    }
    case toml::node_type::string:
      return node.as_string()->get();
    case toml::node_type::integer: {
      // A non-negative integer as unsigned, so a reader that wants one (a seed) takes it.
      const std::int64_t v = node.as_integer()->get();
      if (v >= 0) return static_cast<std::uint64_t>(v);
      return v;
    }
    case toml::node_type::floating_point:
      return node.as_floating_point()->get();
    case toml::node_type::boolean:
      return node.as_boolean()->get();
    case toml::node_type::date:
      return text_of(node.as_date()->get());
    case toml::node_type::time:
      return text_of(node.as_time()->get());
    case toml::node_type::date_time:
      return text_of(node.as_date_time()->get());
    case toml::node_type::none:
      break;
  }
  return nullptr;
}

const char* toml_type_name(const toml::node& node) noexcept {
  switch (node.type()) {
    case toml::node_type::table:
      return "table";
    case toml::node_type::array:
      return "array";
    case toml::node_type::string:
      return "string";
    case toml::node_type::integer:
      return "integer";
    case toml::node_type::floating_point:
      return "float";
    case toml::node_type::boolean:
      return "boolean";
    case toml::node_type::date:
      return "date";
    case toml::node_type::time:
      return "time";
    case toml::node_type::date_time:
      return "date-time";
    case toml::node_type::none:
      break;
  }
  return "nothing";
}

}  // namespace hystbench::daemon::details
