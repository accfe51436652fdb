// Replays every input the fuzzers once found to crash, hang or trip a sanitizer
// (fuzz/regressions/<target>/*) through the same entry points as the fuzz targets.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "support/fuzz_entries.hpp"

namespace fs = std::filesystem;

namespace {

// Runs the entry on the empty input, a few fixed inputs, then every committed crasher;
// returns how many crashers there were. A target's folder must exist (an empty one holds its
// .README): a renamed or lost folder would otherwise replay nothing and pass.
template <typename Entry>
std::size_t replay(const std::string& target, Entry entry) {
  const std::string fixed[] = {"", "\n", "\xff\xfe", std::string(1, '\0'), "{}", "[[[[[[[["};
  for (const auto& s : fixed) {
    (void)entry(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  }
  const fs::path dir = fs::path(HYSTBENCH_SOURCE_DIR) / "fuzz" / "regressions" / target;
  std::size_t n = 0;
  EXPECT_TRUE(fs::is_directory(dir)) << dir << " is missing";
  if (!fs::is_directory(dir)) return n;
  for (const auto& f : fs::directory_iterator(dir)) {
    if (!f.is_regular_file() || f.path().filename().string().front() == '.') continue;
    std::ifstream in(f.path(), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    SCOPED_TRACE(f.path().string());
    (void)entry(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
    ++n;
  }
  return n;
}

// The entry's verdict on a text: true accepted, false refused with the documented error.
template <typename Entry>
bool accepts(Entry entry, const std::string& text) {
  return entry(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
}

std::string file_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

}  // namespace

// The lower bounds are the inputs committed so far: one that goes missing fails the test.
TEST(FuzzRegressions, RequestLines) {
  EXPECT_GE(replay("request", hystbench::fuzz::request_line), 7u);
}
// No config crasher is committed yet: the entry the fuzzer drives must still tell a good file
// from a bad one, or the fuzzer explores nothing past the parser.
TEST(FuzzRegressions, ConfigFiles) {
  replay("config", hystbench::fuzz::config_text);
  const fs::path config = fs::path(HYSTBENCH_SOURCE_DIR) / "config";
  for (const char* shipped : {"loopback.toml", "hystbenchd.toml"}) {
    EXPECT_TRUE(accepts(hystbench::fuzz::config_text, file_text(config / shipped))) << shipped;
  }
  EXPECT_TRUE(accepts(hystbench::fuzz::config_text, ""));  // every key has a default
  EXPECT_FALSE(accepts(hystbench::fuzz::config_text, "[loop]\nrate_hz = -5\n"));
  EXPECT_FALSE(accepts(hystbench::fuzz::config_text, "[loop\n"));
}
TEST(FuzzRegressions, ModelFiles) {
  EXPECT_GE(replay("model_file", hystbench::fuzz::model_file_text), 1u);
}
TEST(FuzzRegressions, CsvFiles) {
  replay("csv", hystbench::fuzz::csv_text);
  EXPECT_TRUE(accepts(hystbench::fuzz::csv_text, "t,u,y\n0,1,2\n0.001,1.5,2.5\n"));
  EXPECT_FALSE(accepts(hystbench::fuzz::csv_text, "t,u\n0.002,1\n0.001,2\n"));  // t falls
  EXPECT_FALSE(accepts(hystbench::fuzz::csv_text, "t,u\n0,abc\n"));
}
