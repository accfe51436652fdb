#pragma once
// Command socket: a Unix domain stream socket speaking JSON lines (one JSON object per '\n').
//
//   on connect   <- {"hello":"hystbenchd","version":"0.1.0","protocol":1}
//   request      -> {"id":7,"cmd":"status","params":{...}}          (id and params optional)
//   reply        <- {"id":7,"ok":true,"result":{...}}
//                <- {"id":7,"ok":false,"error":{"code":"busy","message":"..."}}
//   event        <- {"event":"run.finished",...}                    (no id; broadcast_event())
// Protocol errors are replied with "id": the request's id when it could be read, else null:
//   line_too_long (line > max_line_bytes; the rest of that line is discarded), bad_json
//   (syntax or invalid UTF-8), bad_request (not an object, "cmd" missing / not a string,
//   "params" not an object, "id" not a string / number / null, unknown key), internal (the
//   dispatcher threw), too_many_clients (then the connection is closed).
//
// Threads: one event thread poll()s the listening socket and all (non-blocking) clients and
// calls the dispatcher for each request, in order per client: a slow dispatcher delays every
// client. Never the loop thread. broadcast_event() may be called from any thread.
// Back-pressure: a client's requests are not read while its unsent output exceeds half of
// max_output_bytes; a client whose unsent output would exceed max_output_bytes (it does not
// read its events) is disconnected, never blocking the others. Sends use MSG_NOSIGNAL: a client
// that vanishes mid-reply raises no SIGPIPE.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "hystbench/common/request_limits.hpp"

struct pollfd;

namespace hystbench::daemon {

inline constexpr int kProtocolVersion = 1;

struct Request {
  nlohmann::json id;  ///< as sent (string, number or null; null when absent)
  std::string cmd;
  nlohmann::json params = nlohmann::json::object();  ///< {} when absent
  std::uint64_t client = 0;  ///< connection number, unique for the server's lifetime
};

struct Reply {
  bool ok = true;
  nlohmann::json result = nlohmann::json::object();
  std::string error_code;  ///< machine-readable, e.g. "unknown_cmd", "busy"
  std::string error_message;
  /// Extra keys of the error object, e.g. {"sample": 1234} (an object; code and message win).
  nlohmann::json error_detail = nlohmann::json::object();

  static Reply success(nlohmann::json result = nlohmann::json::object());
  static Reply failure(std::string code, std::string message,
                       nlohmann::json detail = nlohmann::json::object());
};

struct SocketServerOptions {
  std::filesystem::path path;  ///< at most 107 bytes; its folder is created when missing
  unsigned mode = 0660;        ///< file mode of the socket
  std::size_t max_clients = 128;
  /// The longest request line, '\n' excluded.
  std::size_t max_line_bytes = common::kMaxRequestLineBytes;
  std::size_t max_output_bytes = std::size_t{1}
                                 << 20;  ///< unsent bytes per client before disconnect
};

/// The socket cannot be set up: path in use by a live server, not a socket, too long, ...
class SocketServerError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct SocketServerCounters {
  std::uint64_t clients = 0;          ///< connected now
  std::uint64_t accepted = 0;         ///< connections accepted in all
  std::uint64_t refused = 0;          ///< turned away with too_many_clients
  std::uint64_t slow_dropped = 0;     ///< disconnected because their output buffer was full
  std::uint64_t requests = 0;         ///< lines handed to the dispatcher
  std::uint64_t protocol_errors = 0;  ///< line_too_long, bad_json, bad_request
  std::uint64_t events = 0;           ///< broadcast_event() calls
};

class SocketServer {
 public:
  using Dispatcher = std::function<Reply(const Request&)>;
  /// Told the connection number of every client that goes away (it closed, was dropped as
  /// slow, or the server stopped), on the event thread, after its last request was handled.
  using DisconnectHandler = std::function<void(std::uint64_t client)>;

  SocketServer(SocketServerOptions options, Dispatcher dispatcher,
               DisconnectHandler on_disconnect = {});
  /// Calls stop().
  ~SocketServer();
  SocketServer(const SocketServer&) = delete;
  SocketServer& operator=(const SocketServer&) = delete;

  /// Binds and listens (mode set before the first client can connect) and starts the event
  /// thread. A socket file left by a dead server is removed; a live server answering on the
  /// path, or a path that is not a socket, throws SocketServerError (nothing is removed).
  void start();
  /// Closes every client and the socket, removes the socket file (only if it is still ours)
  /// and joins the event thread. Idempotent. From the dispatcher (the event thread itself) it
  /// only asks the thread to end; the destructor or a later stop() joins.
  void stop();

  /// Sends `event` (a JSON object, conventionally {"event": name, ...}) as one line to every
  /// connected client. Thread-safe, never blocks on a client.
  void broadcast_event(const nlohmann::json& event);

  SocketServerCounters counters() const noexcept;
  const std::filesystem::path& path() const noexcept { return options_.path; }

 private:
  struct Client;
  void run() noexcept;
  /// One poll() and what it reports; false when poll() fails (the event thread ends).
  bool serve_round(std::vector<pollfd>& fds);
  void accept_clients();
  void read_client(Client& c);
  void process_lines(Client& c);
  void handle_line(Client& c, std::string_view line);
  void queue(Client& c, const std::string& line);
  void flush(Client& c);
  void deliver_events();
  void close_all();
  void disconnected(std::uint64_t client) noexcept;

  SocketServerOptions options_;
  Dispatcher dispatcher_;
  DisconnectHandler on_disconnect_;
  int listen_fd_ = -1;
  int wake_fd_ = -1;
  unsigned long long socket_inode_ = 0;
  std::mutex lifecycle_mutex_;  // start() / stop()
  std::thread thread_;
  std::atomic<bool> stopping_{false};
  std::vector<std::unique_ptr<Client>> clients_;  // event thread only
  std::uint64_t next_client_ = 1;

  std::mutex events_mutex_;
  std::deque<std::string> events_;  // serialized lines waiting for the event thread

  struct AtomicCounters {
    std::atomic<std::uint64_t> clients{0}, accepted{0}, refused{0}, slow_dropped{0}, requests{0},
        protocol_errors{0}, events{0};
  } counters_;
};

}  // namespace hystbench::daemon
