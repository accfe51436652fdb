#pragma once
// The bench commands of the `hystbench` CLI: they talk to hystbenchd over its socket.
#include <iosfwd>
#include <nlohmann/json.hpp>
#include <string>

namespace hystbench::daemon {

/// Socket path: $HYSTBENCH_SOCKET when set, else /run/hystbench/hystbench.sock.
std::string default_socket_path();

struct RemoteCommand {
  std::string socket_path;
  std::string
      cmd;  ///< status, identify, track, stop, abort, reset, model.get, model.load, config.get
  nlohmann::json params = nlohmann::json::object();
  bool wait = false;  ///< identify/track: follow progress until the run ends, print its result
  bool json_output = false;
};

/// Returns the exit code: 0 ok, 1 refused by the daemon or the run did not complete,
/// 2 cannot reach the daemon.
int run_remote(const RemoteCommand& cmd, std::ostream& out, std::ostream& err);

/// Human-readable summary of a run result (as in the run.finished event).
void print_run_result(const nlohmann::json& result, std::ostream& out);

}  // namespace hystbench::daemon
