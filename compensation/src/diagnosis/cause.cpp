// The candidate causes' names (diagnosis.hpp): what the report and the command line call them,
// in the order they are tested and reported.
#include <array>
#include <optional>
#include <span>
#include <string_view>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::compensation {

namespace {

constexpr std::array<Cause, 7> kCandidates{
    Cause::kAsymmetry, Cause::kLoopShape, Cause::kRateDependence, Cause::kCreep,
    Cause::kDynamics,  Cause::kDelay,     Cause::kDrift};

}  // namespace

std::string_view to_string(Cause cause) noexcept {
  switch (cause) {
    case Cause::kNone:
      return "none";
    case Cause::kAsymmetry:
      return "asymmetry";
    case Cause::kRateDependence:
      return "rate_dependence";
    case Cause::kCreep:
      return "creep";
    case Cause::kDynamics:
      return "dynamics";
    case Cause::kDelay:
      return "delay";
    case Cause::kDrift:
      return "drift";
    case Cause::kLoopShape:
      return "loop_shape";
  }
  return "none";
}

std::optional<Cause> cause_from_string(std::string_view name) noexcept {
  if (name == "none") return Cause::kNone;
  for (const Cause c : kCandidates) {
    if (to_string(c) == name) return c;
  }
  return std::nullopt;
}

std::span<const Cause> candidate_causes() noexcept { return kCandidates; }

}  // namespace hystbench::compensation
