#include "details/diagnosis_candidates.hpp"

#include <cstdio>
#include <stdexcept>

namespace hystbench::compensation::details {

const ResidualProfile& CandidateContext::profile(const std::string& variable) const {
  for (const ResidualProfile& p : profiles) {
    if (p.variable == variable) return p;
  }
  throw std::logic_error("diagnosis: no residual profile '" + variable + "'");
}

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
