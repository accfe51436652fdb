#include "diagnosis/details/naming/decision.hpp"

#include <cmath>

namespace hystbench::compensation::details::diagnosis {

std::string shape_name(Cause shape) {
  return "the loop's shape (" + std::string(to_string(shape)) + ")";
}

double quadrature_difference(double before, double after) {
  return std::sqrt(std::max(0.0, before * before - after * after));
}

VerdictCase Decision::verdict_case() const noexcept {
  if (at_floor) return VerdictCase::kAtNoiseFloor;
  if (eligible.empty()) return VerdictCase::kNothingEligible;
  return beyond ? VerdictCase::kBeyondTheShape : VerdictCase::kLargestGain;
}

Cause Decision::named_cause() const noexcept {
  switch (verdict_case()) {
    case VerdictCase::kAtNoiseFloor:
    case VerdictCase::kNothingEligible:
      return Cause::kNone;
    case VerdictCase::kBeyondTheShape:
      return beyond->cause;
    case VerdictCase::kLargestGain:
      break;
  }
  return eligible.front()->cause;
}

bool plane_outdone(const Diagnosis& d) {
  const CandidateReport* plane = d.candidate(Cause::kLoopShape);
  const CandidateReport* plays = d.candidate(Cause::kAsymmetry);
  return plane != nullptr && plays != nullptr && plane->significant && plays->significant &&
         plane->heldout.rmse * kPlaneOverPlays > plays->heldout.rmse;
}

std::size_t index_of(const Diagnosis& d, Cause c) {
  std::size_t i = 0;
  while (d.candidates[i].cause != c) ++i;
  return i;
}

const OnTopOfShape* on_shape_of(const Naming& x, Cause c) {
  for (const OnTopOfShape& o : x.on_shape) {
    if (o.cause == c) return &o;
  }
  return nullptr;
}

void set_extended(Diagnosis& d, const details::ExtensionFit& joint) {
  d.extended = joint.model;
  d.extended_fit = joint.fit;
  d.extended_heldout = joint.heldout;
  d.extended_prediction = joint.prediction;
}

details::CandidateContext on_joint(const Diagnosis& d, const Naming& x, const Joint& joint,
                                   std::span<const double> residual,
                                   const std::vector<ResidualProfile>& profiles) {
  return {x.r,
          joint.fit.spec,
          joint.fit,
          joint.fit.prediction,
          residual,
          x.ev,
          profiles,
          x.response,
          d.noise_rms,
          x.reference_delay_samples,
          added_gain_needed(x.options)};
}

}  // namespace hystbench::compensation::details::diagnosis
