#pragma once
// Several records of one device diagnosed together (diagnosis internals): where each one lies
// in their concatenation, and their outputs' sensor offsets aligned onto the first's. Not
// real-time: fits the baseline twice.
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details {

/// One record's samples [begin, end) in the concatenation.
struct RecordPart {
  std::string name;
  std::size_t begin = 0, end = 0;
};

/// Where each part begins, in order.
std::vector<std::size_t> starts_of(const std::vector<RecordPart>& parts);

/// Sensor offsets differ between runs: each record's output is shifted onto the first's by its
/// mean residual against the baseline fitted on all (twice: the fit moves with the shifts).
/// Returns the shift of each record (0 for the first) [output unit]; y is shifted in place.
std::vector<double> align_offsets(std::span<const double> t, std::span<const double> u,
                                  std::vector<double>& y, const DiagnosisOptions& options,
                                  const std::vector<RecordPart>& parts);

}  // namespace hystbench::compensation::details
