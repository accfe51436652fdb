#pragma once
// identify's run: the standard excitation over [u_min, u_max] after a short ramp from the
// present output, recorded from the first sample for the fit. Pure (no threads, no files);
// errors are CommandError naming the key. Not real-time safe.
#include <nlohmann/json.hpp>
#include <string>

#include "hystbench/sim/identification_excitation.hpp"
#include "runs/details/request_params.hpp"
#include "runs/details/run_context.hpp"

namespace hystbench::daemon::details {

/// An identify request with the configured defaults filled in.
struct IdentifyRequest {
  std::string model;    ///< a fit family or "auto" (details/fit_families.hpp)
  int operators = 0;    ///< 0 = chosen by held-out error
  int dead_zones = -1;  ///< -1 = chosen by held-out error
  double u_min = 0.0,
         u_max = 0.0;  ///< excitation span [V], within the output limits, u_min < u_max
  /// Diagnose the record with the fitted model and adopt the extension when it tracks better.
  bool extend = true;
  /// The request named the family (not auto): the extension keeps it, and never swaps the
  /// operator for a Preisach plane (loop_shape).
  bool family_fixed = false;
};

/// The request's keys over settings' identify defaults; bad_params naming the key when the
/// model is unknown or the span is not inside the output limits.
IdentifyRequest parse_identify_request(const RequestParams& request, const BenchSettings& settings);

/// identify's excitation for the request (the configured segments, a rate-law segment for a
/// family that fits one) [V]; bad_params when its options are refused.
sim::Excitation identify_excitation(const IdentifyRequest& request, const RunContext& ctx);

/// The identify program, with what its fit needs (BuiltRun::fit).
BuiltRun make_identify_program(const IdentifyRequest& request, const RunContext& ctx);

}  // namespace hystbench::daemon::details
