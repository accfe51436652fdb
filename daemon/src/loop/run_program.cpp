#include "hystbench/daemon/loop/run_program.hpp"

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

}  // namespace hystbench::daemon
