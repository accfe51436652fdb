#pragma once
// main() of every program: run(argc, argv), and whatever exception escapes it printed as
// "<name>: <what>" (an unknown one as "<name>: unknown exception") on stderr with exit code 1,
// the stack unwound on the way (destructors close logs and put drivers in their safe state).
#include <exception>
#include <iostream>

namespace hystbench::common {

inline int run_main(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << name << ": " << e.what() << "\n";
  } catch (...) {
    std::cerr << name << ": unknown exception\n";
  }
  return 1;
}

}  // namespace hystbench::common
