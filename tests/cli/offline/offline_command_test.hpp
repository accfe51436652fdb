#pragma once
// A fixture for the offline commands' tests: a fresh folder per test (TempDirTest) and run(),
// which calls a command body as the CLI does and keeps what it wrote to err.
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <utility>

#include "support/temp_dir_test.hpp"

namespace hystbench::test {

class OfflineCommandTest : public TempDirTest {
 protected:
  explicit OfflineCommandTest(std::string prefix) : TempDirTest(std::move(prefix)) {}

  /// Runs f(out, err); returns its exit code, parses its JSON line into *result (when given and
  /// the code is 0), and keeps err in err_.
  template <typename F>
  int run(F&& f, nlohmann::json* result = nullptr) {
    std::ostringstream out, err;
    const int code = f(out, err);
    err_ = err.str();
    if (result != nullptr && code == 0) *result = nlohmann::json::parse(out.str());
    return code;
  }

  std::string err_;
};

}  // namespace hystbench::test
