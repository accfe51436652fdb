// docs/reference/protocol.md against the daemon's command table: every command has a section,
// and every parameter table on the page is the one the command table makes now (key, type,
// range, default, meaning). HYSTBENCH_UPDATE_DOCS=1 writes the tables made now into the page
// instead of failing (scripts/protocol-reference.sh).
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "service/details/command_table.hpp"
#include "service/details/protocol_tables.hpp"

namespace hdd = hystbench::daemon::details;

namespace {

const std::string kPage = std::string(HYSTBENCH_SOURCE_DIR) + "/docs/reference/protocol.md";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The first line of the first difference between a and b, for the failure message.
std::string first_difference(const std::string& a, const std::string& b) {
  std::istringstream sa(a), sb(b);
  std::string la, lb;
  for (int line = 1;; ++line) {
    const bool ga = static_cast<bool>(std::getline(sa, la));
    const bool gb = static_cast<bool>(std::getline(sb, lb));
    if (!ga && !gb) return "none";
    if (!ga || !gb || la != lb) {
      return "line " + std::to_string(line) + ":\n  page: " + (ga ? la : "<end>") +
             "\n  made: " + (gb ? lb : "<end>");
    }
  }
}

}  // namespace

TEST(ProtocolReference, EveryCommandHasASection) {
  const std::string page = read_file(kPage);
  ASSERT_FALSE(page.empty()) << kPage << " is missing or empty";
  for (const hdd::Command& c : hdd::bench_commands()) {
    bool found = false;
    std::istringstream lines(page);
    for (std::string line; std::getline(lines, line);) {
      found = found || (line.rfind("### ", 0) == 0 &&
                        line.find("`" + std::string(c.name) + "`") != std::string::npos);
    }
    EXPECT_TRUE(found) << "no \"### `" << c.name << "`\" section";
  }
}

TEST(ProtocolReference, EveryParameterTableIsTheOneTheCommandTableMakes) {
  const std::string page = read_file(kPage);
  ASSERT_FALSE(page.empty()) << kPage << " is missing or empty";
  std::vector<std::string> missing;
  const std::string made = hdd::with_parameter_tables(page, &missing);
  EXPECT_TRUE(missing.empty()) << "no marked table for '" << missing.front() << "': add the lines\n"
                               << hdd::table_begin_marker(missing.front()) << "\n"
                               << hdd::kTableEndMarker;
  const char* update = std::getenv("HYSTBENCH_UPDATE_DOCS");
  if (update != nullptr && std::string(update) == "1" && made != page) {
    std::ofstream(kPage) << made;
    GTEST_SKIP() << "wrote the tables made now into " << kPage;
  }
  EXPECT_TRUE(made == page) << kPage << " differs from the command table at "
                            << first_difference(page, made)
                            << "\nrun scripts/protocol-reference.sh to write the tables";
}

TEST(ProtocolReference, ATableListsEveryKeyOfEveryRowOfItsCommandOnce) {
  const std::string track = hdd::parameter_table("track");
  for (const char* key : {"`reference`", "`reference_upload`", "`reference_uploads`", "`kp`",
                          "`learn_trials`", "`decoupling`", "`frequencies_hz`"}) {
    const std::size_t at = track.find(std::string("| ") + key + " |");
    ASSERT_NE(at, std::string::npos) << key;
    EXPECT_EQ(track.find(std::string("| ") + key + " |", at + 1), std::string::npos) << key;
  }
  // The row without a condition (a built-in reference) comes first.
  EXPECT_LT(track.find("`reference`"), track.find("`reference_upload`"));
  EXPECT_EQ(hdd::parameter_table("status"), "");
  // A constant default in backticks beside the one that depends on the request.
  EXPECT_NE(track.find("| `0.8`; 0.2 for `step` |"), std::string::npos) << track;
  // identify's families as the program lists them.
  EXPECT_NE(hdd::parameter_table("identify").find("`preisach`"), std::string::npos);
}
