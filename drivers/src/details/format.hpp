#pragma once
// Numbers in messages: fixed-point with a given number of digits (not real-time: allocates).
#include <cstdio>
#include <string>

namespace hystbench::drivers::details {

inline std::string fixed(double v, int digits) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

}  // namespace hystbench::drivers::details
