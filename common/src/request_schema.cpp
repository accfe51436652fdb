#include "hystbench/common/request_schema.hpp"

#include <charconv>
#include <stdexcept>

namespace hystbench::common {

std::string_view default_constant(const ParamSpec& spec) {
  if (spec.fallback == nullptr) {
    throw std::logic_error(std::string("request parameter '") + spec.key +
                           "' has no constant default: give the fallback");
  }
  return spec.fallback;
}

double default_number(const ParamSpec& spec) {
  const std::string_view text = default_constant(spec);
  double v = 0.0;
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (error != std::errc() || end != text.data() + text.size()) {
    throw std::logic_error(std::string("request parameter '") + spec.key + "': default '" +
                           std::string(text) + "' is not a number");
  }
  return v;
}

const ParamSpec& find_param(std::span<const ParamSpec> table, std::string_view key) {
  for (const ParamSpec& p : table) {
    if (key == p.key) return p;
  }
  throw std::logic_error("request parameter '" + std::string(key) + "' is not in its table");
}

std::string default_text(const ParamSpec& spec, bool markdown) {
  std::string out;
  if (spec.fallback != nullptr) {
    out = markdown ? "`" + std::string(spec.fallback) + "`" : std::string(spec.fallback);
  }
  if (spec.fallback_doc != nullptr) {
    std::string words = spec.fallback_doc;
    if (!markdown) std::erase(words, '`');
    out += (out.empty() ? "" : "; ") + words;
  }
  return out;
}

}  // namespace hystbench::common
