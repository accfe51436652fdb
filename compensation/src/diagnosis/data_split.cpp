// The record's split into fit and held-out parts (DataSplit, diagnosis.hpp): which samples are
// held out or skipped, and the line the report describes the split with.
#include <string>

#include "diagnosis/details/number_text.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation {

using details::num;

bool DataSplit::is_heldout(std::size_t k) const noexcept {
  for (const auto& [b, e] : heldout) {
    if (k < b) return false;
    if (k < e) return true;
  }
  return false;
}

bool DataSplit::is_skipped(std::size_t k) const noexcept {
  for (const auto& [b, e] : skipped_ranges) {
    if (k < b) return false;
    if (k < e) return true;
  }
  return false;
}

std::string DataSplit::describe(double sample_period_s) const {
  std::string s = "record cut into " + std::to_string(blocks) + " equal blocks, " +
                  std::to_string(heldout.size()) + " interleaved ones held out (" +
                  num(100.0 * static_cast<double>(heldout_samples) / static_cast<double>(samples)) +
                  " % of " + std::to_string(samples) + " samples): t =";
  for (std::size_t i = 0; i < heldout.size(); ++i) {
    s += (i ? ", " : " ") + num(static_cast<double>(heldout[i].first) * sample_period_s) + "-" +
         num(static_cast<double>(heldout[i].second) * sample_period_s) + " s";
  }
  if (skipped > 0 && records > 1) {
    s += "; the start of each of the " + std::to_string(records) + " records (" +
         num(static_cast<double>(skipped) * sample_period_s) +
         " s in all, until its input has reached both its extremes) neither fitted nor scored";
  } else if (skipped > 0) {
    s += "; the first " + num(static_cast<double>(skipped) * sample_period_s) +
         " s (until the input has reached both its extremes) neither fitted nor scored";
  }
  return s + "; every model is fitted on the other blocks and simulated through the whole record";
}

}  // namespace hystbench::compensation
