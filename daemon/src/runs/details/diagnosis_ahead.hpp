#pragma once
// The diagnoses of identify's candidates, run on a worker thread while the loop plays their
// verification segments (wall time the supervisor spends waiting): one candidate after another,
// in the order given, each kept until taken; candidates fitted after it started join the queue
// (queue_more); once the verification has chosen, only the chosen one (focus). The worker waits
// for more until it is taken or destroyed, and diagnoses on one thread (the loop has the other
// core); one abandoned or cancelled stops at its next fit. A diagnosis taken before it started
// runs on every core, the loop idle then. The worker runs at the normal policy: at SCHED_IDLE
// another busy process starves it, and taking or cancelling it then waits for as long. Not
// real-time code; the supervisor thread owns it.
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/compensation/diagnosis.hpp"

namespace hystbench::daemon::details {

class DiagnosisAhead {
 public:
  using Progress = std::function<void(double, const std::string&)>;
  /// How a diagnosis is run (the DiagnosisOptions fields of the same names).
  struct Controls {
    Progress progress;                ///< may throw to cancel
    std::function<bool()> cancelled;  ///< polled inside the fits; may be empty
    std::size_t threads = 1;
  };
  /// Diagnoses candidate i under the given controls.
  using Task = std::function<compensation::Diagnosis(std::size_t, const Controls&)>;

  /// Starts the worker on the candidates in `order`.
  DiagnosisAhead(Task task, std::vector<std::size_t> order);
  /// Cancels what is running (at its next progress report) and joins.
  ~DiagnosisAhead();
  /// The candidates in `order` join the queue, diagnosed from now on by `task`, which must give
  /// what the task before gave for the candidates it knew. Ignored once focused or taken.
  void queue_more(Task task, const std::vector<std::size_t>& order);
  /// Only candidate i is wanted from now on: another one running is abandoned (at its next
  /// progress report) and none but i starts.
  void focus(std::size_t candidate);
  /// True once candidate i's diagnosis has finished (or failed).
  bool ready(std::size_t candidate);
  DiagnosisAhead(const DiagnosisAhead&) = delete;
  DiagnosisAhead& operator=(const DiagnosisAhead&) = delete;

  /// Candidate i's diagnosis, and when it ran: during the verification, partly (waited for),
  /// or after it, on the calling thread and every core (reporting to `progress`) when it had not
  /// started: a worker still busy with another one is cancelled, not waited for. Stops the
  /// worker: only one is taken. Throws what the diagnosis threw.
  struct Taken {
    compensation::Diagnosis diagnosis;
    std::string how;  ///< "during the verification", "partly ..." or "after the verification"
  };
  Taken take(std::size_t candidate, const Progress& progress);

 private:
  struct Cancelled {};
  void run();
  void cancel();
  void stop_and_join();

  std::shared_ptr<const Task> task_;  ///< the latest; the worker holds the one it runs
  std::deque<std::size_t> queue_;     ///< the candidates still to start, in order
  bool focused_ = false;              ///< focus() was called: no candidate joins any more
  std::mutex mutex_;
  std::condition_variable changed_;
  std::map<std::size_t, compensation::Diagnosis> done_;
  std::map<std::size_t, std::exception_ptr> failed_;
  std::optional<std::size_t> running_;
  bool stop_after_running_ = false;  ///< take() waits for the one running: no further one
  bool cancel_ = false;              ///< abandon the one running and stop
  bool abandon_ = false;             ///< abandon the one running, go on with the queue
  std::thread worker_;
};

}  // namespace hystbench::daemon::details
