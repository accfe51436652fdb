#pragma once
// The bench commands of the `hystbench` CLI: they talk to hystbenchd over its socket.
#include <functional>
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon {

class BenchClient;

/// Socket path: $HYSTBENCH_SOCKET when set, else /run/hystbench/hystbench.sock.
std::string default_socket_path();

struct RemoteCommand {
  std::string socket_path;
  std::string
      cmd;  ///< status, identify, track, stop, abort, reset, model.get, model.load, config.get
  nlohmann::json params = nlohmann::json::object();
  bool wait = false;  ///< identify/track: follow progress until the run ends, print its result
  bool json_output = false;
  /// track --wait: when the run ends, its log's plots go here (plot_run_log); empty = none.
  std::string plot_dir;
};

/// Returns the exit code: 0 ok, 1 refused by the daemon or the run did not complete,
/// 2 cannot reach the daemon.
int run_remote(const RemoteCommand& cmd, std::ostream& out, std::ostream& err);

/// Follows the events of run `run_id` until its run.finished and returns the run's result;
/// `progress` (may be empty) gets each run.progress / fit.progress as (fraction 0..1, what).
/// Throws ClientError when the daemon goes away.
nlohmann::json wait_for_run(BenchClient& client, const std::string& run_id,
                            const std::function<void(double, const std::string&)>& progress);

/// Draws a progress bar on a terminal line (carriage return, no newline).
void progress_bar(std::ostream& err, double fraction, const std::string& label);

/// Human-readable summary of a run result (as in the run.finished event).
void print_run_result(const nlohmann::json& result, std::ostream& out);

}  // namespace hystbench::daemon
