#include "hystbench/daemon/loop/run_program.hpp"

#include <algorithm>

namespace hystbench::daemon {

const char* to_string(RunKind kind) noexcept {
  switch (kind) {
    case RunKind::kIdentify:
      return "identify";
    case RunKind::kTrack:
      return "track";
    case RunKind::kExcite:
      return "excite";
    case RunKind::kFrequencyResponse:
      return "frf";
  }
  return "unknown";
}

const char* to_string(RunEnd end) noexcept {
  switch (end) {
    case RunEnd::kCompleted:
      return "completed";
    case RunEnd::kStopped:
      return "stopped";
    case RunEnd::kAborted:
      return "aborted";
    case RunEnd::kFault:
      return "fault";
  }
  return "unknown";
}

double RunProgram::feedforward_target(double t_s, double tare_um) const noexcept {
  const sim::SignalGenerator& r = feedforward_reference ? *feedforward_reference : *reference;
  if (!preview) return std::clamp(r.value(t_s), y_ref_min, y_ref_max) - tare_um;
  const double tl = t_s + preview->lead_s(), h = preview->step_s();
  return preview->target(r.value(tl - h), r.value(tl), r.value(tl + h)) - tare_um;
}

}  // namespace hystbench::daemon
