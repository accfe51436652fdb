#pragma once
// The wall clock's time as logs and results state it. Not real-time safe.
#include <string>

namespace hystbench::daemon::details {

/// Now in UTC, ISO 8601 to the second: "2026-01-01T00:00:00Z".
std::string utc_now_iso8601();

}  // namespace hystbench::daemon::details
