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
// returns how many crashers there were.
std::size_t replay(const std::string& target, Entry entry) {
  const std::string fixed[] = {"", "\n", "\xff\xfe", std::string(1, '\0'), "{}", "[[[[[[[["};
  for (const auto& s : fixed) entry(reinterpret_cast<const std::uint8_t*>(s.data()), s.size());
  const fs::path dir = fs::path(HYSTBENCH_SOURCE_DIR) / "fuzz" / "regressions" / target;
  std::size_t n = 0;
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

TEST(FuzzRegressions, RequestLines) {
  std::cout << replay("request", hystbench::fuzz::request_line) << " crashers replayed\n";
}
TEST(FuzzRegressions, ConfigFiles) {
  std::cout << replay("config", hystbench::fuzz::config_text) << " crashers replayed\n";
}
TEST(FuzzRegressions, ModelFiles) {
  std::cout << replay("model_file", hystbench::fuzz::model_file_text) << " crashers replayed\n";
}
TEST(FuzzRegressions, CsvFiles) {
  std::cout << replay("csv", hystbench::fuzz::csv_text) << " crashers replayed\n";
}
