#include "diagnosis/details/after_reversals.hpp"

#include <algorithm>
#include <cmath>

namespace hystbench::compensation::details {

WindowError after_reversals_error(const DiagnosisRecord& r, const InputEvents& ev,
                                  std::span<const double> prediction, std::size_t window) {
  double square = 0.0;
  WindowError out;
  std::size_t scored_until = 0;  // windows of close reversals overlap: each sample counts once
  for (const std::size_t k : ev.event_samples) {
    if (ev.step[k]) continue;
    const std::size_t end = std::min(r.n, k + 1 + window);
    for (std::size_t j = std::max(k + 1, scored_until); j < end; ++j) {
      if (r.part[j] != kHeldoutPart) continue;
      const double e = r.y[j] - prediction[j];
      square += e * e;
      ++out.samples;
    }
    scored_until = std::max(scored_until, end);
  }
  if (out.samples > 0) out.rms = std::sqrt(square / static_cast<double>(out.samples));
  return out;
}

}  // namespace hystbench::compensation::details
