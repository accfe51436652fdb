// docs/reference/protocol.md against the daemon's command table: every command has a section,
// every parameter a row there with its type and range as the daemon checks them, and the page
// lists no parameter the daemon would refuse as unknown.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "service/details/command_table.hpp"

namespace hdd = hystbench::daemon::details;

namespace {

struct Section {
  std::set<std::string> commands;             // the backticked names in its heading
  std::map<std::string, std::string> params;  // key -> "type | range"
};

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(' ');
  const auto e = s.find_last_not_of(' ');
  return b == std::string::npos ? "" : s.substr(b, e - b + 1);
}

std::vector<std::string> backticked(const std::string& line) {
  std::vector<std::string> out;
  for (std::size_t a = line.find('`'); a != std::string::npos; a = line.find('`', a + 1)) {
    const std::size_t b = line.find('`', a + 1);
    if (b == std::string::npos) break;
    out.push_back(line.substr(a + 1, b - a - 1));
    a = b;
  }
  return out;
}

// The "### `cmd`" sections of the page and the "| `key` | type | range | meaning |" rows in each.
std::vector<Section> read_sections(const std::string& path) {
  std::ifstream in(path);
  std::vector<Section> sections;
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("### ", 0) == 0) {
      Section s;
      for (const auto& name : backticked(line)) s.commands.insert(name);
      sections.push_back(s);
      continue;
    }
    if (sections.empty() || line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::stringstream row(line.substr(1));
    for (std::string cell; std::getline(row, cell, '|');) cells.push_back(trim(cell));
    if (cells.size() < 3) continue;
    const std::vector<std::string> key = backticked(cells[0]);
    if (key.size() == 1) sections.back().params[key[0]] = cells[1] + " | " + cells[2];
  }
  return sections;
}

const char* type_name(hdd::ParamType t) {
  switch (t) {
    case hdd::ParamType::kNumber:
      return "number";
    case hdd::ParamType::kInteger:
      return "integer";
    case hdd::ParamType::kString:
      return "string";
    case hdd::ParamType::kObject:
      return "object";
    case hdd::ParamType::kArray:
      return "array";
    case hdd::ParamType::kBoolean:
      return "boolean";
  }
  return "?";
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%g", v);
  return buf;
}

// "lo to hi", "≥ lo", "≤ hi" or "" as the page writes a range (numbers only have one).
std::string range(const hdd::ParamSpec& p) {
  if (p.type != hdd::ParamType::kNumber && p.type != hdd::ParamType::kInteger) return "";
  const bool lo = std::isfinite(p.lo), hi = std::isfinite(p.hi);
  if (lo && hi) return number(p.lo) + " to " + number(p.hi);
  if (lo) return "≥ " + number(p.lo);
  if (hi) return "≤ " + number(p.hi);
  return "";
}

}  // namespace

TEST(ProtocolReference, ListsEveryCommandAndParameterAsTheDaemonChecksThem) {
  const std::vector<Section> sections =
      read_sections(std::string(HYSTBENCH_SOURCE_DIR) + "/docs/reference/protocol.md");
  ASSERT_FALSE(sections.empty()) << "docs/reference/protocol.md has no command sections";
  std::map<std::string, std::set<std::string>> known;  // command -> its keys over every row
  for (const hdd::Command& c : hdd::bench_commands()) {
    const Section* section = nullptr;
    for (const Section& s : sections) {
      if (s.commands.count(c.name) != 0) section = &s;
    }
    ASSERT_NE(section, nullptr) << "no section for the command '" << c.name << "'";
    known[c.name];
    for (const hdd::ParamSpec& p : c.params) {
      known[c.name].insert(p.key);
      const auto row = section->params.find(p.key);
      ASSERT_NE(row, section->params.end()) << c.name << ": no row for '" << p.key << "'";
      EXPECT_EQ(row->second, std::string(type_name(p.type)) + " | " + range(p))
          << c.name << "." << p.key << ": type | range";
    }
  }
  for (const Section& s : sections) {
    for (const auto& [key, cells] : s.params) {
      bool listed = false;
      for (const auto& name : s.commands) listed = listed || known[name].count(key) != 0;
      EXPECT_TRUE(listed) << "the page lists '" << key
                          << "', which no command in its section takes";
    }
  }
}
