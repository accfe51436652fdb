#pragma once
// The live view in a browser (docs/reference/web-view.md): an HTTP server (cpp-httplib) that
// serves the page compiled into the daemon, answers the bench's read-only commands as JSON,
// streams the scope and the bench's events as server-sent events, and, where control is on and
// the request carries the token, passes commands to the same command table as the socket.
//
// Threads: a listening thread and a pool of max_clients connection threads; a stream holds one
// of them while it is open (at most max_clients - 1 streams, so requests still get through).
// Nothing here runs on, or waits for, the loop thread: the scope comes from a ScopeFeed.
// A client that does not read or send within io_timeout is dropped; a body over
// max_body_bytes is refused (413); an unknown path is refused (404) naming the ones there are.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace httplib {
class Server;
struct Request;
struct Response;
}  // namespace httplib

namespace hystbench::daemon {

class Bench;
class ScopeFeed;

struct WebViewOptions {
  std::string host = "127.0.0.1";
  int port = 0;                 ///< [0, 65535]; 0 = a free one (address() tells which)
  bool control = false;         ///< commands that change the bench are accepted (with the token)
  std::string token;            ///< required (>= kMinAccessTokenLength) when control is on
  std::size_t max_clients = 8;  ///< connection threads, [2, 64]
  std::size_t max_body_bytes = std::size_t{64} << 10;
  std::chrono::seconds io_timeout{5};
  /// Each connection's kernel send buffer [bytes]: what a client that stops reading can hold
  /// up before the view waits io_timeout and drops it.
  int send_buffer_bytes = 64 << 10;
  std::filesystem::path log_dir;  ///< the runs' sample logs (their plots)
  /// What /api/view reports.
  std::string driver = "loopback";
  double rate_hz = 10000.0;
  double scope_rate_hz = 500.0;
  std::vector<std::string> axes = {""};
  /// Frames per second of the scope stream, [1, 100].
  double frame_rate_hz = 30.0;
};

/// The view cannot start: a bad option, or the address cannot be bound (named, with the cause).
class WebViewError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct WebViewCounters {
  std::uint64_t requests = 0;         ///< requests answered, refusals included
  std::uint64_t refused = 0;          ///< answered with a 4xx or 5xx status
  std::uint64_t streams = 0;          ///< streams open now
  std::uint64_t streams_opened = 0;   ///< streams opened in all
  std::uint64_t streams_dropped = 0;  ///< streams ended because the client stopped reading
};

class WebView {
 public:
  /// The bench and the feed must outlive the view; the feed may be null (no scope: the stream
  /// sends events only). Throws WebViewError for options out of range.
  WebView(WebViewOptions options, Bench& bench, ScopeFeed* feed);
  /// Calls stop().
  ~WebView();
  WebView(const WebView&) = delete;
  WebView& operator=(const WebView&) = delete;

  /// Binds the address and starts serving. Throws WebViewError naming the address and cause.
  void start();
  /// Ends every stream, closes the listening socket and joins the threads. Idempotent.
  void stop();
  /// "HOST:PORT" as bound (after start()).
  std::string address() const;
  /// Sends one of the bench's events (a JSON object) to every stream. Any thread; never blocks
  /// on a client (the last 64 wait for the streams).
  void publish(const nlohmann::json& event);
  WebViewCounters counters() const noexcept;

 private:
  void add_routes();
  void stream(const httplib::Request& req, httplib::Response& res);
  void command(const httplib::Request& req, httplib::Response& res);
  /// The stream's next piece for a reader at these cursors: new events and a scope frame.
  std::string next_piece(std::uint64_t& event_cursor, std::uint64_t& scope_cursor);

  WebViewOptions options_;
  Bench& bench_;
  ScopeFeed* feed_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int bound_port_ = 0;
  std::atomic<bool> stopping_{false};

  mutable std::mutex events_mutex_;
  std::deque<std::string> events_;  // serialized, the newest last
  std::uint64_t events_next_ = 0;   // events published so far

  struct AtomicCounters {
    std::atomic<std::uint64_t> requests{0}, refused{0}, streams{0}, streams_opened{0},
        streams_dropped{0};
  } counters_;
};

}  // namespace hystbench::daemon
