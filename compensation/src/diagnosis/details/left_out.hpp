#pragma once
// Leave-one-record-out scoring of the diagnosis (internals): a set of records of one device is
// diagnosed end to end; each candidate's structure is also fitted on all records but one and
// scored on that one, which it never saw. Not real-time: allocates a copy of the others per
// record once, then one linear fit per structure and record.
#include <cstddef>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/record.hpp"
#include "diagnosis/details/record_set.hpp"

namespace hystbench::compensation::details {

class LeftOutScorer {
 public:
  /// `r` is the concatenation of `parts` (at least two). Throws std::invalid_argument when the
  /// others of some record are too short to fit (make_diagnosis_record's checks).
  LeftOutScorer(const DiagnosisRecord& r, std::vector<RecordPart> parts,
                const DiagnosisOptions& options);

  /// For each part in order: rms error [output unit] of `spec` fitted on the other parts and
  /// simulated through this part alone (from rest at its first input), after its start-up,
  /// its mean error removed. std::nullopt when the structure cannot be fitted on some others.
  std::optional<std::vector<double>> rms(const ExtensionSpec& spec) const;

 private:
  struct Others {
    std::vector<double> t, u, y;
    DiagnosisRecord record;
  };
  const DiagnosisRecord& r_;
  std::vector<RecordPart> parts_;
  std::vector<std::unique_ptr<Others>> others_;  // stable: each record spans its own vectors
};

/// Leave-one-record-out scores of every candidate's structure (fits, in d.candidates' order)
/// against the baseline's (base), for a set of records (parts, at least two): sets each
/// candidate's left_out, left_out_gain and carries_over, and notes in d what the set shows (a
/// baseline that cannot be fitted with a record left out, or that predicts some record left out
/// far worse than its own held-out blocks).
void score_left_out(Diagnosis& d, const DiagnosisRecord& r, const std::vector<RecordPart>& parts,
                    const ExtensionSpec& base, const std::vector<ExtensionFit>& fits,
                    const DiagnosisOptions& options);

}  // namespace hystbench::compensation::details
