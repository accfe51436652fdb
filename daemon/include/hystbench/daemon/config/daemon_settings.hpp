#pragma once
// Maps the daemon configuration file onto the bench's settings.
#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/config/config.hpp"

namespace hystbench::daemon {

/// A plain mapping: parse_config() has already checked every key and range, so this cannot fail
/// for a configuration it returned.
BenchSettings bench_settings_from(const DaemonConfig& config);

}  // namespace hystbench::daemon
