#pragma once
// The reasons the report gives (diagnosis internals): why a candidate is not named, built from
// what the naming procedure decided, and the lists those reasons and the verdict name. Not
// real-time: allocates strings.
#include <string>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

/// "a, b and c".
std::string joined(const std::vector<std::string>& names);

/// Each record left out whole and the candidate's gain there: "run 1 1.3, run 2 1.2".
std::string left_out_summary(const CandidateReport& c);

/// Why a candidate is not named: what it adds to the model holding `before` (added_rms, [unit])
/// is within the noise (less than `allowance`).
std::string within_noise(const std::string& before, double added_rms, double allowance,
                         const std::string& unit);

/// What judging a cause after the first decided (judge_contender), and the figures it decided on.
struct AddedJudgement {
  enum class Verdict {
    kNamed,
    kWithinNoise,   ///< what it adds is less than the noise allows
    kBelowMinGain,  ///< its own gain is below min_gain, and what it adds below `needed`
    kMostlyTheirs,  ///< its own gain is mostly the causes' before it: it adds less than `needed`
  };
  Verdict verdict = Verdict::kNamed;
  double gain = 0.0;        ///< its own held-out gain, the one it is ranked by
  bool over_shape = false;  ///< that gain is over the loop's shape, not the reference
  double added_gain = 0.0;  ///< held-out gain added to the model holding the causes before it
  double added_rms = 0.0;   ///< held-out rms explained beyond them [output unit]
  double needed = 0.0;      ///< the added gain it needs (added_gain_needed)
  double allowance = 0.0;   ///< the noise allowance [output unit]
  double min_gain = 0.0;    ///< DiagnosisOptions::min_gain
};

/// Why a cause judged as `j` (not kNamed) is not named; `before` names the causes before it.
std::string not_named_reason(const AddedJudgement& j, const std::string& before,
                             const std::string& unit);

}  // namespace hystbench::compensation::details::diagnosis
