#pragma once
// The runs since the daemon started, newest first: each run's result as run.finished gave it,
// a one-line summary of it for lists, and the faults among them. Bounded (the oldest go first).
// Thread-safe (its own lock); not real-time safe.
#include <cstddef>
#include <deque>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon::details {

class RunHistory {
 public:
  /// Keeps the last max_runs results and the last max_faults faults, both >= 1.
  explicit RunHistory(std::size_t max_runs = 200, std::size_t max_faults = 50);

  /// A finished run's result (an object with run_id, kind, end, reason, ...). Stamped with the
  /// time it is added (UTC).
  void add(const nlohmann::json& result);
  /// {"runs": [{"run_id", "kind", "end", "reason", "finished", "rms_error_percent", "log"}, ...]},
  /// newest first. rms_error_percent: a tracking run's, else the model's; identify's
  /// verification's; a stage's worst axis's (a stage identify's fits' held-out); else null.
  nlohmann::json runs() const;
  /// The result of run `run_id`; throws CommandError unknown_run naming the ones kept.
  nlohmann::json run(const std::string& run_id) const;
  /// [{"time", "run_id", "kind", "reason"}, ...], newest first: the runs that ended in a fault.
  nlohmann::json faults() const;

 private:
  struct Entry {
    nlohmann::json summary;
    nlohmann::json result;
  };
  std::size_t max_runs_;
  std::size_t max_faults_;
  mutable std::mutex mutex_;
  std::deque<Entry> runs_;             // newest first
  std::deque<nlohmann::json> faults_;  // newest first
};

}  // namespace hystbench::daemon::details
