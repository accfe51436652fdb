#pragma once
// Client side of the command socket (what `hystbench status|identify|track|...` uses).
// Blocking, one connection, JSON lines; events that arrive while waiting for a reply are kept
// and returned by next_event() in order.
#include <chrono>
#include <deque>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>
#include <string>

namespace hystbench::cli {

class ClientError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class BenchClient {
 public:
  /// Connects and reads the greeting. Throws ClientError naming the socket path and the cause
  /// (no daemon listening, permission denied, not a hystbenchd socket).
  explicit BenchClient(const std::string& socket_path);
  ~BenchClient();
  BenchClient(const BenchClient&) = delete;
  BenchClient& operator=(const BenchClient&) = delete;

  /// Sends {"id":n,"cmd":cmd,"params":params} and returns the whole reply object
  /// ({"id","ok","result"|"error"}). Throws ClientError when the connection fails.
  nlohmann::json request(const std::string& cmd,
                         const nlohmann::json& params = nlohmann::json::object(),
                         std::chrono::milliseconds timeout = std::chrono::seconds(30));
  /// The next event line, or nullopt on timeout. Throws ClientError when the daemon goes away.
  std::optional<nlohmann::json> next_event(std::chrono::milliseconds timeout);
  const nlohmann::json& greeting() const { return greeting_; }

 private:
  std::optional<nlohmann::json> read_line(std::chrono::milliseconds timeout);

  std::string path_;
  int fd_ = -1;
  std::string buffer_;
  std::deque<nlohmann::json> events_;
  nlohmann::json greeting_;
  long long next_id_ = 1;
};

}  // namespace hystbench::cli
