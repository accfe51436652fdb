#pragma once
// What the bench's components (the identify coordinator, the learning runs) share with the
// bench: its settings, its loop, its run supervisor and the mutex that guards the bench's state.
// The bench owns them all and outlives its components.
#include <mutex>

#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"

namespace hystbench::daemon::details {

class RunSupervisor;

struct BenchParts {
  const BenchSettings& settings;
  BenchLoop& loop;
  RunSupervisor& runs;
  std::mutex& mutex;  ///< the bench's: it guards the run supervisor and the components' state
  /// The loop's period [s].
  double dt() const noexcept { return 1.0 / settings.loop.rate_hz; }
};

}  // namespace hystbench::daemon::details
