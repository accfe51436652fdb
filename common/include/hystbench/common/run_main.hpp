#pragma once
// main() of a device simulator: run(argc, argv); an exception is printed as "<name>: <what>" on
// stderr and exits 1.
#include <exception>
#include <iostream>

namespace hystbench::apps {

inline int run_main(const char* name, int (*run)(int, char**), int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << name << ": " << e.what() << "\n";
    return 1;
  }
}

}  // namespace hystbench::apps
