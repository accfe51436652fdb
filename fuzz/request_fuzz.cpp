// libFuzzer target: see tests/support/fuzz_entries.hpp (request_line).
#include "support/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hystbench::fuzz::request_line(data, size);
  return 0;
}
