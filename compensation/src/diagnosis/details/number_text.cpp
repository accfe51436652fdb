#include "diagnosis/details/number_text.hpp"

#include <cstdio>

namespace hystbench::compensation::details {

std::string num(double v, int digits) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.*g", digits, v);
  return buf;
}

std::string percent(double fraction) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f %%", 100.0 * fraction);
  return buf;
}

}  // namespace hystbench::compensation::details
