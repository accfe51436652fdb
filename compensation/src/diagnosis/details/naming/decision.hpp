#pragma once
// The naming procedure's state (diagnosis internals): what the verdict is decided on (Decision),
// what naming the causes after the first needs (Naming), the extended model as they join it
// (Joint), and the thresholds every step shares. The steps: eligible_candidates, the ordered
// rules (rules.hpp), test_on_shape, decide (decide.hpp), name_causes_and_extend. Not real-time.
#include <algorithm>
#include <cstddef>
#include <string>
#include <vector>

#include "diagnosis/details/candidates.hpp"
#include "diagnosis/details/extension_fit.hpp"
#include "diagnosis/details/record.hpp"
#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation::details::diagnosis {

// The plane is named as the shape only where it predicts the held-out blocks this much better
// than the play family's own shape extension: a plane's hundreds of cells stand for a few plays
// and dead zones no better than they do themselves.
inline constexpr double kPlaneOverPlays = 1.1;
// A runner-up this close to the named cause's gain makes the verdict ambiguous.
inline constexpr double kAmbiguity = 0.9;
// A cause after stronger ones is named when, added to them, it gains this much (or min_gain
// when lower): an effect beside a larger one gains little over the baseline on its own, and one
// whose own gain was mostly theirs (a rate law widening the loop as a delay does) adds little.
inline constexpr double kMinAddedGain = 1.1;

/// What a cause after the first must add: kMinAddedGain, or min_gain when lower.
inline double added_gain_needed(const DiagnosisOptions& options) {
  return std::min(options.min_gain, kMinAddedGain);
}

/// The causes that change the loop's shape: the play family's own extension (asymmetry) and the
/// operator swapped for a Preisach plane (loop_shape).
inline bool is_shape(Cause c) { return c == Cause::kAsymmetry || c == Cause::kLoopShape; }

/// What the other causes are judged against when the first is named beyond the shape (the
/// NamedCause::against of those causes).
std::string shape_name(Cause shape);

/// sqrt(before^2 - after^2), 0 when after > before: the rms one model explains beyond another.
double quadrature_difference(double before, double after);

/// A cause tested again on top of the loop's shape (the asymmetry extension).
struct OnTopOfShape {
  Cause cause = Cause::kNone;
  details::CandidateOutcome outcome;  ///< its fit holds the shape and the cause
  double gain = 0.0;                  ///< shape's held-out rms / this held-out rms
  bool significant = false;           ///< its statistic, read from the shape's residual

  bool counts(const DiagnosisOptions& options) const {
    return significant && gain >= options.min_gain;
  }
};

/// Which case of the verdict a decision is, in the order they are checked.
enum class VerdictCase {
  kAtNoiseFloor,     ///< the baseline's held-out error is at the noise floor: none
  kNothingEligible,  ///< no candidate may be named: none
  kBeyondTheShape,   ///< the first cause is named on top of the loop's shape (Decision::beyond)
  kLargestGain,      ///< the eligible candidate of the largest gain is named
};

/// What the verdict and the notes are decided on.
struct Decision {
  double reference = 0.0;  ///< held-out rms the gains are judged against: baseline or refit
  bool at_floor = false;   ///< the baseline's held-out error is at the noise floor
  std::vector<const CandidateReport*> eligible;  ///< may be named, largest gain first
  std::vector<OnTopOfShape> on_shape;            ///< the other causes on top of the shape
  const OnTopOfShape* beyond = nullptr;          ///< the strongest of those that counts
  Cause shape = Cause::kAsymmetry;               ///< the eligible shape cause on_shape holds
  const CandidateReport* best_any = nullptr;     ///< the largest gain of all

  VerdictCase verdict_case() const noexcept;
  /// The cause the verdict names: none at the noise floor or without an eligible candidate, else
  /// the cause named beyond the shape, else the eligible one of the largest gain.
  Cause named_cause() const noexcept;
};

/// What naming the causes beyond the first and joining their extensions need.
struct Naming {
  const details::DiagnosisRecord& r;
  const std::vector<details::ExtensionFit>& fits;  ///< each candidate's, in candidate order
  const details::InputEvents& ev;
  const std::vector<ResidualProfile>& profiles;  ///< of the reference residual
  const FrequencyResponse& response;             ///< of the reference prediction
  const DiagnosisOptions& options;
  double reference = 0.0;      ///< held-out rms the candidates' gains are judged against
  std::string reference_name;  ///< what that is: the baseline, or the given model refitted
  const std::vector<OnTopOfShape>& on_shape;
  const OnTopOfShape* beyond = nullptr;  ///< the first cause, named beyond the shape
  double reference_delay_samples = 0.0;  ///< the reference's own input delay [samples]
  Cause shape = Cause::kAsymmetry;       ///< the shape cause `on_shape` was tested on
};

/// The extended model as the causes after the first join it.
struct Joint {
  details::ExtensionFit fit;       ///< the joint model so far, predicted and scored
  std::string named_extension;     ///< what the first cause's extension (and the shape's) adds
  std::vector<std::string> added;  ///< what each part joined after it adds
};

/// A cause after the first, tried on top of the joint model.
struct Next {
  std::size_t index;  ///< in Diagnosis::candidates
  double gain;        ///< over the reference (or the shape): the gain it is ranked by
  bool contender;     ///< it may be named; else it may only join the extended model
  /// Not significant on the reference's residual: its statistic is read again on the joint
  /// model's, and it is a contender when significant there.
  bool retest = false;
};

/// The plane and the play family's own shape extension both significant, and the plane not
/// kPlaneOverPlays better on the held-out blocks.
bool plane_outdone(const Diagnosis& d);

/// Where cause c stands in d.candidates (it is there).
std::size_t index_of(const Diagnosis& d, Cause c);

/// Cause c tested on top of the shape, or nullptr when it was not.
const OnTopOfShape* on_shape_of(const Naming& x, Cause c);

/// The extended model's model, errors and prediction from a joint fit (not its description).
void set_extended(Diagnosis& d, const details::ExtensionFit& joint);

/// A test's context with the joint model so far as its baseline: `residual` is y - its
/// prediction, `profiles` the residual profiles the statistic is read from.
details::CandidateContext on_joint(const Diagnosis& d, const Naming& x, const Joint& joint,
                                   std::span<const double> residual,
                                   const std::vector<ResidualProfile>& profiles);

}  // namespace hystbench::compensation::details::diagnosis
