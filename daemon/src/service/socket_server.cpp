#include "hystbench/daemon/service/socket_server.hpp"

#include <fcntl.h>
#include <poll.h>
#include <spdlog/spdlog.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <system_error>
#include <vector>

#include "service/details/json_lines.hpp"

namespace hystbench::daemon {

namespace {

constexpr std::size_t kReadChunk = std::size_t{64} << 10;
constexpr std::size_t kMaxQueuedEvents = 4096;

std::system_error sys_error(const std::string& what) {
  return std::system_error(errno, std::generic_category(), what);
}

sockaddr_un address_of(const std::filesystem::path& path) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const std::string& s = path.native();
  if (s.empty() || s.size() >= sizeof(addr.sun_path)) {
    throw SocketServerError("socket path '" + s + "' must be 1 to " +
                            std::to_string(sizeof(addr.sun_path) - 1) + " bytes long");
  }
  std::memcpy(addr.sun_path, s.c_str(), s.size() + 1);
  return addr;
}

// Removes a socket file left by a dead server; refuses a live one or anything not a socket.
void remove_stale_socket(const std::filesystem::path& path, const sockaddr_un& addr) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) {
    if (errno == ENOENT) return;
    throw sys_error("cannot inspect " + path.string());
  }
  if (!S_ISSOCK(st.st_mode)) {
    throw SocketServerError(path.string() + " exists and is not a socket; not removing it");
  }
  const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (probe < 0) throw sys_error("socket");
  const int rc = ::connect(probe, reinterpret_cast<const sockaddr*>(&addr), sizeof addr);
  const int err = errno;
  ::close(probe);
  // EAGAIN: the listener's backlog is full, so it is alive.
  if (rc == 0 || err == EAGAIN || err == EINPROGRESS) {
    throw SocketServerError("another server is listening on " + path.string());
  }
  if (err != ECONNREFUSED) {
    throw std::system_error(err, std::generic_category(), "cannot probe " + path.string());
  }
  if (::unlink(path.c_str()) != 0 && errno != ENOENT) {
    throw sys_error("cannot remove stale socket " + path.string());
  }
  spdlog::info("removed stale socket {}", path.string());
}

void wake(int event_fd) {
  const std::uint64_t one = 1;
  [[maybe_unused]] const auto n = ::write(event_fd, &one, sizeof one);
}

}  // namespace

// ---------------------------------------------------------------------------------------------

Reply Reply::success(nlohmann::json result) { return {true, std::move(result), {}, {}}; }

Reply Reply::failure(std::string code, std::string message, nlohmann::json detail) {
  return {false, nlohmann::json::object(), std::move(code), std::move(message), std::move(detail)};
}

struct SocketServer::Client {
  int fd = -1;
  std::uint64_t id = 0;
  std::string in;           // received bytes not yet handled
  bool discarding = false;  // inside an over-long line: drop until the next '\n'
  bool eof = false;         // the peer will send nothing more
  bool dead = false;        // close now
  std::string out;          // bytes to send, from out_offset on
  std::size_t out_offset = 0;
  std::size_t pending() const { return out.size() - out_offset; }
};

SocketServer::SocketServer(SocketServerOptions options, Dispatcher dispatcher,
                           DisconnectHandler on_disconnect)
    : options_(std::move(options)),
      dispatcher_(std::move(dispatcher)),
      on_disconnect_(std::move(on_disconnect)) {
  if (!dispatcher_) throw std::invalid_argument("SocketServer needs a dispatcher");
  if (options_.max_clients == 0 || options_.max_line_bytes == 0 ||
      options_.max_output_bytes < 2 * kReadChunk) {
    throw std::invalid_argument(
        "SocketServer: max_clients and max_line_bytes must be > 0, "
        "max_output_bytes >= 128 KiB");
  }
  // Lives as long as the object, so broadcast_event() never races with stop().
  wake_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
  if (wake_fd_ < 0) throw sys_error("eventfd");
}

SocketServer::~SocketServer() {
  stop();
  ::close(wake_fd_);
}

void SocketServer::start() {
  std::lock_guard lifecycle(lifecycle_mutex_);
  if (thread_.joinable() || listen_fd_ >= 0) throw SocketServerError("server already started");
  const sockaddr_un addr = address_of(options_.path);
  if (options_.path.has_parent_path()) {
    std::error_code ec;
    std::filesystem::create_directories(options_.path.parent_path(), ec);
    if (ec) throw std::system_error(ec, "cannot create " + options_.path.parent_path().string());
  }
  remove_stale_socket(options_.path, addr);

  listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (listen_fd_ < 0) throw sys_error("socket");
  try {
    if (::bind(listen_fd_, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0) {
      throw sys_error("cannot bind " + options_.path.string());
    }
    struct stat st {};
    // Mode first, listen after: no client can connect through a wider mode.
    if (::chmod(options_.path.c_str(), options_.mode) != 0 ||
        ::stat(options_.path.c_str(), &st) != 0) {
      const auto e = sys_error("cannot set the mode of " + options_.path.string());
      ::unlink(options_.path.c_str());
      throw e;
    }
    socket_inode_ = st.st_ino;
    if (::listen(listen_fd_, 128) != 0) {
      const auto e = sys_error("cannot listen on " + options_.path.string());
      ::unlink(options_.path.c_str());
      throw e;
    }
    stopping_.store(false);
    thread_ = std::thread([this] { run(); });
  } catch (...) {
    ::close(listen_fd_);
    listen_fd_ = -1;
    throw;
  }
  spdlog::info("listening on {}", options_.path.string());
}

void SocketServer::stop() {
  stopping_.store(true);
  wake(wake_fd_);
  if (thread_.joinable() && std::this_thread::get_id() == thread_.get_id()) return;  // dispatcher
  std::lock_guard lifecycle(lifecycle_mutex_);
  if (!thread_.joinable()) return;
  thread_.join();
  // Remove the socket file only if it is still the one we bound (a newer server may own it).
  struct stat st {};
  if (::lstat(options_.path.c_str(), &st) == 0 && st.st_ino == socket_inode_) {
    ::unlink(options_.path.c_str());
  }
  ::close(listen_fd_);
  listen_fd_ = -1;
  spdlog::info("socket {} closed", options_.path.string());
}

void SocketServer::broadcast_event(const nlohmann::json& event) {
  std::string line = details::json_line(event);
  {
    std::lock_guard lock(events_mutex_);
    if (events_.size() >= kMaxQueuedEvents) events_.pop_front();  // event thread stalled
    events_.push_back(std::move(line));
  }
  counters_.events.fetch_add(1, std::memory_order_relaxed);
  wake(wake_fd_);
}

SocketServerCounters SocketServer::counters() const noexcept {
  const auto get = [](const std::atomic<std::uint64_t>& a) {
    return a.load(std::memory_order_relaxed);
  };
  return {get(counters_.clients),      get(counters_.accepted), get(counters_.refused),
          get(counters_.slow_dropped), get(counters_.requests), get(counters_.protocol_errors),
          get(counters_.events)};
}

// --- event thread ----------------------------------------------------------------------------

void SocketServer::run() noexcept {
  std::vector<pollfd> fds;
  bool serving = true;
  while (serving && !stopping_.load()) {
    // Only an allocation can fail here (std::bad_alloc, std::length_error): the dispatcher's
    // exceptions are its replies. A round that fails may have handled part of a client's lines,
    // so every connection closes rather than serve a line twice; the server goes on listening.
    try {
      serving = serve_round(fds);
    } catch (const std::exception& e) {
      spdlog::error("socket server: {}: closing every connection", e.what());
      close_all();
    } catch (...) {
      spdlog::error("socket server: unknown exception: closing every connection");
      close_all();
    }
  }
  // Last words: events broadcast before stop() (e.g. the result of the run a shutdown ended)
  // still reach the clients that read them; one non-blocking attempt each, never waiting.
  try {
    deliver_events();
    for (const auto& c : clients_) {
      if (!c->dead) flush(*c);
    }
  } catch (...) {
    spdlog::warn("socket server: the last events could not be sent");
  }
  close_all();
}

bool SocketServer::serve_round(std::vector<pollfd>& fds) {
  fds.clear();
  fds.push_back({wake_fd_, POLLIN, 0});
  fds.push_back({listen_fd_, POLLIN, 0});
  for (const auto& c : clients_) {
    short events = 0;
    // Back-pressure: read no more requests while the replies pile up.
    if (!c->eof && c->pending() <= options_.max_output_bytes / 2) events |= POLLIN;
    if (c->pending() > 0) events |= POLLOUT;
    fds.push_back({c->fd, events, 0});
  }
  if (::poll(fds.data(), fds.size(), -1) < 0) {
    if (errno == EINTR) return true;
    spdlog::error("socket server: poll failed: {}", std::strerror(errno));
    return false;
  }
  if (fds[0].revents & POLLIN) {
    std::uint64_t count = 0;
    [[maybe_unused]] const auto n = ::read(wake_fd_, &count, sizeof count);
    deliver_events();
  }
  if (fds[1].revents & POLLIN) accept_clients();
  // fds[2 + i] belongs to clients_[i]: clients accepted just now come after them.
  for (std::size_t i = 0; i + 2 < fds.size(); ++i) {
    Client& c = *clients_[i];
    const short revents = fds[i + 2].revents;
    if (c.dead) continue;
    if (revents & (POLLIN | POLLHUP | POLLERR)) read_client(c);
    if (!c.dead && (revents & POLLOUT)) flush(c);
    // Output drained below the mark: handle the lines that were held back.
    if (!c.dead && !c.in.empty() && c.pending() <= options_.max_output_bytes / 2) {
      process_lines(c);
    }
    if (!c.dead && c.eof && c.pending() == 0 && c.in.empty()) c.dead = true;
  }
  std::erase_if(clients_, [this](const std::unique_ptr<Client>& c) {
    if (!c->dead) return false;
    ::close(c->fd);
    counters_.clients.fetch_sub(1, std::memory_order_relaxed);
    spdlog::debug("socket client {} closed", c->id);
    disconnected(c->id);
    return true;
  });
  return true;
}

void SocketServer::disconnected(std::uint64_t client) noexcept {
  if (!on_disconnect_) return;
  try {
    on_disconnect_(client);
  } catch (const std::exception& e) {
    spdlog::error("socket client {}: disconnect handler failed: {}", client, e.what());
  } catch (...) {
    spdlog::error("socket client {}: disconnect handler failed", client);
  }
}

void SocketServer::close_all() {
  for (const auto& c : clients_) {
    ::close(c->fd);
    disconnected(c->id);
  }
  counters_.clients.store(0, std::memory_order_relaxed);
  clients_.clear();
}

void SocketServer::accept_clients() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) {
      if (errno == EINTR || errno == ECONNABORTED) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) {
        spdlog::warn("socket server: accept failed: {}", std::strerror(errno));
      }
      return;
    }
    if (clients_.size() >= options_.max_clients) {
      const std::string line =
          details::error_line(nullptr, "too_many_clients",
                              "the server has " + std::to_string(options_.max_clients) +
                                  " clients already; try again later");
      counters_.refused.fetch_add(1, std::memory_order_relaxed);
      [[maybe_unused]] const auto n = ::send(fd, line.data(), line.size(), MSG_NOSIGNAL);
      ::close(fd);
      continue;
    }
    auto c = std::make_unique<Client>();
    c->fd = fd;
    c->id = next_client_++;
    counters_.accepted.fetch_add(1, std::memory_order_relaxed);
    counters_.clients.fetch_add(1, std::memory_order_relaxed);
    queue(*c, details::json_line({{"hello", "hystbenchd"},
                                  {"version", HYSTBENCH_VERSION},
                                  {"protocol", kProtocolVersion}}));
    spdlog::debug("socket client {} connected", c->id);
    clients_.push_back(std::move(c));
  }
}

void SocketServer::read_client(Client& c) {
  char buffer[kReadChunk];
  const ssize_t n = ::recv(c.fd, buffer, sizeof buffer, 0);
  if (n < 0) {
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return;
    c.dead = true;  // ECONNRESET and friends
    return;
  }
  if (n == 0) {
    c.eof = true;
    // A last line without '\n' before the end still counts.
    if (!c.in.empty() && !c.discarding) c.in += '\n';
    if (c.discarding) c.in.clear();
  } else {
    c.in.append(buffer, static_cast<std::size_t>(n));
  }
  process_lines(c);
}

void SocketServer::process_lines(Client& c) {
  std::size_t start = 0;
  while (!c.dead && c.pending() <= options_.max_output_bytes / 2) {
    const std::size_t newline = c.in.find('\n', start);
    if (newline == std::string::npos) break;
    std::string_view line(c.in.data() + start, newline - start);
    start = newline + 1;
    if (c.discarding) {  // the end of an over-long line
      c.discarding = false;
      continue;
    }
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.size() > options_.max_line_bytes) {
      counters_.protocol_errors.fetch_add(1, std::memory_order_relaxed);
      queue(c,
            details::error_line(nullptr, "line_too_long",
                                "request line longer than " +
                                    std::to_string(options_.max_line_bytes) + " bytes; discarded"));
      continue;
    }
    if (line.find_first_not_of(" \t") == std::string_view::npos) continue;  // blank line
    handle_line(c, line);
  }
  c.in.erase(0, start);
  // A partial line already longer than allowed: answer now, drop it and what follows up to '\n'.
  if (!c.discarding && c.in.find('\n') == std::string::npos &&
      c.in.size() > options_.max_line_bytes + 1) {
    counters_.protocol_errors.fetch_add(1, std::memory_order_relaxed);
    queue(c,
          details::error_line(nullptr, "line_too_long",
                              "request line longer than " +
                                  std::to_string(options_.max_line_bytes) + " bytes; discarded"));
    c.discarding = true;
  }
  if (c.discarding) {
    const std::size_t newline = c.in.find('\n');
    if (newline == std::string::npos) {
      c.in.clear();
    } else {
      c.in.erase(0, newline + 1);
      c.discarding = false;
    }
  }
}

void SocketServer::handle_line(Client& c, std::string_view line) {
  Request request;
  details::ProtocolError error;
  if (!details::parse_request(line, request, error)) {
    counters_.protocol_errors.fetch_add(1, std::memory_order_relaxed);
    queue(c, details::error_line(error.id, error.code, error.message));
    return;
  }
  request.client = c.id;
  counters_.requests.fetch_add(1, std::memory_order_relaxed);
  std::string reply;
  try {
    reply = details::reply_line(request.id, dispatcher_(request));
  } catch (const std::exception& e) {
    reply = details::error_line(request.id, "internal", e.what());
  } catch (...) {
    reply = details::error_line(request.id, "internal", "unknown exception");
  }
  if (reply.size() > options_.max_output_bytes / 2) {
    reply = details::error_line(request.id, "reply_too_large",
                                "the reply has " + std::to_string(reply.size()) + " bytes");
  }
  queue(c, reply);
}

void SocketServer::queue(Client& c, const std::string& line) {
  if (c.dead) return;
  if (c.pending() + line.size() > options_.max_output_bytes) {
    spdlog::warn("socket client {} does not read its output ({} bytes unsent): disconnecting", c.id,
                 c.pending());
    counters_.slow_dropped.fetch_add(1, std::memory_order_relaxed);
    c.dead = true;
    return;
  }
  if (c.out_offset > 0 && c.out_offset >= c.out.size() / 2) {  // compact
    c.out.erase(0, c.out_offset);
    c.out_offset = 0;
  }
  c.out += line;
  flush(c);
}

void SocketServer::flush(Client& c) {
  while (c.pending() > 0) {
    const ssize_t n =
        ::send(c.fd, c.out.data() + c.out_offset, c.pending(), MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n < 0) {
      if (errno == EINTR) continue;
      if (errno != EAGAIN && errno != EWOULDBLOCK) c.dead = true;  // EPIPE, ECONNRESET
      return;
    }
    c.out_offset += static_cast<std::size_t>(n);
  }
  c.out.clear();
  c.out_offset = 0;
}

void SocketServer::deliver_events() {
  std::deque<std::string> events;
  {
    std::lock_guard lock(events_mutex_);
    events.swap(events_);
  }
  for (const auto& line : events) {
    for (const auto& c : clients_) queue(*c, line);
  }
}

}  // namespace hystbench::daemon
