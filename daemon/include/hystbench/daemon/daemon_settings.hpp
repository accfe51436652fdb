#pragma once
// Maps the daemon configuration file onto the bench's settings.
#include "hystbench/daemon/bench.hpp"
#include "hystbench/daemon/config.hpp"

namespace hystbench::daemon {

/// Throws ConfigError naming the key when the combination is invalid.
BenchSettings bench_settings_from(const DaemonConfig& config);

}  // namespace hystbench::daemon
