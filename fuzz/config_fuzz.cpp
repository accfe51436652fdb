// libFuzzer target: see tests/support/fuzz_entries.hpp (config_text).
#include "support/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  (void)hystbench::fuzz::config_text(data, size);
  return 0;
}
