#include "hystbench/compensation/number_text.hpp"

#include <fmt/format.h>

namespace hystbench::compensation {

std::string significant(double v, int digits) { return fmt::format("{:.{}g}", v, digits); }

std::string fixed(double v, int digits) { return fmt::format("{:.{}f}", v, digits); }

std::string percent(double fraction, int digits) {
  return significant(100.0 * fraction, digits) + " %";
}

std::string shortest(double v) { return fmt::format("{}", v); }

}  // namespace hystbench::compensation
