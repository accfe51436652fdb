// Replays every input the fuzzers once found to crash, hang or trip a sanitizer
// (fuzz/regressions/<target>/*) through the same entry points as the fuzz targets.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "support/fuzz_entries.hpp"

namespace fs = std::filesystem;

namespace {

using Entry = void (*)(const std::uint8_t*, std::size_t);

// Runs the entry on the empty input, a few fixed inputs, then every committed crasher;
// returns how many crashers there were. A target's folder must exist (an empty one holds its
// .README): a renamed or lost folder would otherwise replay nothing and pass.
std::size_t replay(const std::string& target, Entry entry) {
  const std::string fixed[] = {"", "\n", "\xff\xfe", std::string(1, '\0'), "{}", "[[[[[[[["};
  for (const auto& s : fixed) entry(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  const fs::path dir = fs::path(HYSTBENCH_SOURCE_DIR) / "fuzz" / "regressions" / target;
  std::size_t n = 0;
  EXPECT_TRUE(fs::is_directory(dir)) << dir << " is missing";
  if (!fs::is_directory(dir)) return n;
  for (const auto& f : fs::directory_iterator(dir)) {
    if (!f.is_regular_file() || f.path().filename().string().front() == '.') continue;
    std::ifstream in(f.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(f.path().string());
    entry(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    ++n;
  }
  return n;
}

}  // namespace

// The lower bounds are the inputs committed so far: one that goes missing fails the test.
TEST(FuzzRegressions, RequestLines) {
  EXPECT_GE(replay("request", hystbench::fuzz::request_line), 7u);
}
TEST(FuzzRegressions, ConfigFiles) {
  EXPECT_GE(replay("config", hystbench::fuzz::config_text), 0u);
}
TEST(FuzzRegressions, ModelFiles) {
  EXPECT_GE(replay("model_file", hystbench::fuzz::model_file_text), 1u);
}
TEST(FuzzRegressions, CsvFiles) { replay("csv", hystbench::fuzz::csv_text); }
