#pragma once
// What a call refuses with: the message of the std::invalid_argument it throws, "" when it
// throws none (another exception propagates).
#include <stdexcept>
#include <string>

namespace hystbench::test {

template <class Call>
std::string invalid_argument_message(const Call& call) {
  try {
    call();
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

}  // namespace hystbench::test
