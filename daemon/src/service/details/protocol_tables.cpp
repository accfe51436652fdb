#include "service/details/protocol_tables.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "service/details/command_table.hpp"

namespace hystbench::daemon::details {

namespace {

constexpr const char* kTypeNames[] = {"number", "integer", "string", "object", "array", "boolean"};

// "lo to hi", "≥ lo", "≤ hi" or "" (numbers and integers only have one).
std::string range_text(const ParamSpec& p) {
  if (p.type != ParamType::kNumber && p.type != ParamType::kInteger) return "";
  const bool lo = std::isfinite(p.lo), hi = std::isfinite(p.hi);
  if (lo && hi) return fmt::format("{:g} to {:g}", p.lo, p.hi);
  if (lo) return fmt::format("≥ {:g}", p.lo);
  if (hi) return fmt::format("≤ {:g}", p.hi);
  return "";
}

std::string meaning_text(const ParamSpec& p) {
  std::string out = p.doc;
  if (p.values == nullptr) return out;
  std::string values;
  for (const std::string& v : p.values()) values += (values.empty() ? "`" : ", `") + v + "`";
  return out + ": " + values;
}

}  // namespace

std::vector<std::string> commands_with_parameters() {
  std::vector<std::string> out;
  for (const Command& c : bench_commands()) {
    if (!c.params.empty() && std::find(out.begin(), out.end(), c.name) == out.end()) {
      out.emplace_back(c.name);
    }
  }
  return out;
}

std::string parameter_table(std::string_view name) {
  std::vector<const Command*> rows;
  for (const Command& c : bench_commands()) {
    if (name == c.name) rows.push_back(&c);
  }
  std::stable_partition(rows.begin(), rows.end(),
                        [](const Command* c) { return c->when_key == nullptr; });
  std::vector<std::string_view> listed;
  std::string out;
  for (const Command* c : rows) {
    for (const ParamSpec& p : c->params) {
      if (std::find(listed.begin(), listed.end(), p.key) != listed.end()) continue;
      listed.emplace_back(p.key);
      out +=
          fmt::format("| `{}` | {} | {} | {} | {} |\n", p.key, kTypeNames[static_cast<int>(p.type)],
                      range_text(p), common::default_text(p, true), meaning_text(p));
    }
  }
  if (out.empty()) return out;
  return "| parameter | type | range | default | meaning |\n| --- | --- | --- | --- | --- |\n" +
         out;
}

std::string table_begin_marker(std::string_view name) {
  return fmt::format(
      "<!-- the parameters of `{}`, generated from the daemon's command table "
      "(scripts/protocol-reference.sh) -->",
      name);
}

std::string with_parameter_tables(const std::string& page, std::vector<std::string>* missing) {
  std::string out = page;
  for (const std::string& name : commands_with_parameters()) {
    const std::string begin = table_begin_marker(name) + "\n";
    const std::size_t from = out.find(begin);
    const std::size_t to =
        from == std::string::npos ? std::string::npos : out.find(kTableEndMarker, from);
    if (to == std::string::npos) {
      if (missing != nullptr) missing->push_back(name);
      continue;
    }
    const std::size_t body = from + begin.size();
    out.replace(body, to - body, parameter_table(name));
  }
  return out;
}

}  // namespace hystbench::daemon::details
