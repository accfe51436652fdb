// libFuzzer target: see tests/support/fuzz_entries.hpp (csv_text).
#include "support/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)hystbench::fuzz::csv_text(data, size);
  return 0;
}
