#pragma once
// The runs, newest first: each run's result as run.finished gave it, a one-line summary of it
// for lists, and the faults among them. Bounded (the oldest go first). With a folder, each
// result is also kept there as <run_id>.result.json ({"finished", "result"}) and the newest of
// them are read back at construction: the list outlives a restart. Thread-safe (its own lock);
// not real-time safe.
#include <cstddef>
#include <deque>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon::details {

class RunHistory {
 public:
  /// Keeps the last max_runs results and the last max_faults faults, both >= 1; `folder` (empty:
  /// none) holds them across restarts: the newest max_runs there are read now (a file that is not
  /// one of them is skipped, named in the log).
  explicit RunHistory(std::filesystem::path folder = {}, std::size_t max_runs = 200,
                      std::size_t max_faults = 50);

  /// A finished run's result (an object with run_id, kind, end, reason, ...). Stamped with the
  /// time it is added (UTC) and written to the folder (a failure is logged: the run's own log
  /// holds its samples whatever happens here).
  void add(const nlohmann::json& result);
  /// {"runs": [{"run_id", "kind", "end", "reason", "finished", "rms_error_percent", "log"}, ...]},
  /// newest first. rms_error_percent: see headline_error() in run_history.cpp (a track's, an
  /// identify's verification, an excite's model error, a stage's worst axis); else null.
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
  /// The entry and, for a fault, the fault log's line (mutex_ held).
  void keep(const nlohmann::json& result, const std::string& finished);
  void read_folder();

  std::filesystem::path folder_;
  std::size_t max_runs_;
  std::size_t max_faults_;
  mutable std::mutex mutex_;
  std::deque<Entry> runs_;             // newest first
  std::deque<nlohmann::json> faults_;  // newest first
};

}  // namespace hystbench::daemon::details
