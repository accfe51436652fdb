// libFuzzer target: see tests/support/fuzz_entries.hpp (model_file_text).
#include "support/fuzz_entries.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  hystbench::fuzz::model_file_text(data, size);
  return 0;
}
