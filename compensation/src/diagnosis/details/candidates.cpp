#include "diagnosis/details/candidates.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>

namespace hystbench::compensation::details {

const ResidualProfile& CandidateContext::profile(const std::string& variable) const {
  for (const ResidualProfile& p : profiles) {
    if (p.variable == variable) return p;
  }
  throw std::logic_error("diagnosis: no residual profile '" + variable + "'");
}

std::size_t simplest_within(const std::vector<ExtensionFit>& fits, double parsimony) {
  double best = std::numeric_limits<double>::infinity();
  for (const ExtensionFit& f : fits) best = std::min(best, f.fit.rmse);
  std::size_t i = 0;
  while (i + 1 < fits.size() && !(fits[i].fit.rmse <= best * (1.0 + parsimony))) ++i;
  return i;
}

}  // namespace hystbench::compensation::details
