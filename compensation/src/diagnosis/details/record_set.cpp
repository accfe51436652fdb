#include "diagnosis/details/record_set.hpp"

#include <algorithm>

#include "diagnosis/details/baseline.hpp"
#include "diagnosis/details/record.hpp"

namespace hystbench::compensation::details {

std::vector<std::size_t> starts_of(const std::vector<RecordPart>& parts) {
  std::vector<std::size_t> starts;
  starts.reserve(parts.size());
  for (const RecordPart& p : parts) starts.push_back(p.begin);
  return starts;
}

std::vector<double> align_offsets(std::span<const double> t, std::span<const double> u,
                                  std::vector<double>& y, const DiagnosisOptions& options,
                                  const std::vector<RecordPart>& parts) {
  const std::vector<std::size_t> starts = starts_of(parts);
  std::vector<double> total(parts.size(), 0.0);
  for (int iteration = 0; iteration < 2; ++iteration) {
    const details::DiagnosisRecord r = details::make_diagnosis_record(t, u, y, options, starts);
    std::vector<double> prediction;
    if (options.baseline && options.baseline->valid()) {
      prediction = ActuatorModel(*options.baseline).simulate(u, r.dt);
    } else {
      prediction = details::fit_pi_baseline(r).fit.prediction;
    }
    std::vector<double> mean(parts.size(), 0.0);
    for (std::size_t i = 0; i < parts.size(); ++i) {
      std::size_t n = 0;
      for (std::size_t k = parts[i].begin; k < parts[i].end; ++k) {
        if (r.part[k] == details::kSkippedPart) continue;
        mean[i] += y[k] - prediction[k], ++n;
      }
      mean[i] /= static_cast<double>(std::max<std::size_t>(n, 1));
    }
    for (std::size_t i = 1; i < parts.size(); ++i) {
      const double shift = mean[i] - mean[0];
      for (std::size_t k = parts[i].begin; k < parts[i].end; ++k) y[k] -= shift;
      total[i] += shift;
    }
  }
  return total;
}

}  // namespace hystbench::compensation::details
