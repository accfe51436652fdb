#pragma once
// What the bench's components (the identify coordinator, the learning runs) share with the
// bench: its settings, its loop, its run supervisor and the mutex that guards the bench's state;
// and what the components that start runs ask of it (RunHooks). The bench owns them all and
// outlives its components.
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>

#include "hystbench/daemon/config/bench_settings.hpp"
#include "hystbench/daemon/loop/bench_loop.hpp"

namespace hystbench::daemon::details {

class RunSupervisor;
struct RunContext;

struct BenchParts {
  const BenchSettings& settings;
  BenchLoop& loop;
  RunSupervisor& runs;
  std::mutex& mutex;  ///< the bench's: it guards the run supervisor and the components' state
  /// The loop's period [s].
  double dt() const noexcept { return 1.0 / settings.loop.rate_hz; }
};

/// What a component that starts runs asks of the bench (each as the bench's own commands use it).
struct RunHooks {
  /// What the run builders need to know. The caller holds the bench's mutex.
  std::function<RunContext()> run_context;
  /// A result, kept and announced (run.finished). No lock held.
  std::function<void(nlohmann::json)> deliver;
};

}  // namespace hystbench::daemon::details
